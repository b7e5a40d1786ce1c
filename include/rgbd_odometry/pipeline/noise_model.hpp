#pragma once
// How each measured 3-D point is wrong: the noise models of the covariance and the fit's weights.
//
// The paper's model (Willis & Brink eq. 2, after Khoshelham & Elberink 2012):
//   sigma_Z = c Z^2,  sigma_X = |X/Z| sigma_Z,  sigma_Y = |Y/Z| sigma_Z,  c = 1.425e-3 / m,
// three independent errors. It leaves out what moves a keypoint's point sideways, which is
// most of a feature method's error.
//
// The physical model follows the measurement P = Z (x_n, y_n, 1):
//  - the keypoint's pixel is off by sigma_px = pixel_sigma_px * scale^level in u and v (its
//    pyramid level's grid), moving P across the viewing ray by sigma_px Z / f;
//  - the depth is off along the ray: axially c Z^2 (Khoshelham & Elberink) and its rounding to
//    the depth map's unit, plus, where the surface is steep in the image, the depth slope
//    |grad Z| (m/px) times the pixel error and times the depth map's own lateral noise
//    (Nguyen, Izadi & Lovell 2012: ~0.8 px). The slope and rounding terms do not vanish with
//    c: a sensor whose depth is exact still samples it at an uncertain pixel;
//  - a capture-time error of the frame's depth moves every depth by its rate dZ/dt times the
//    same error (depth_rate_mps), an error common to the frame, handled by the covariance.
// point_covariance() is the 3x3 form the final fit weights by.
#include <Eigen/Core>
#include <cmath>

#include "rgbd_odometry/pipeline/pipeline_config.hpp"

namespace rgbdo {

// One point's noise as the perturbation kernel draws it:
//   P' = P + (lateral.x n0, lateral.y n1, 0) + ray n2,   n ~ N(0, 1).
struct PointNoise {
  Eigen::Vector2d lateral = Eigen::Vector2d::Zero();  // sigma of X and Y, m
  Eigen::Vector3d ray = Eigen::Vector3d::Zero();      // direction times sigma, m
  double depth_rate_mps = 0;                           // dZ/dt at the keypoint (timing errors)
  Eigen::Matrix3d covariance() const {
    Eigen::Matrix3d c = ray * ray.transpose();
    c(0, 0) += lateral.x() * lateral.x();
    c(1, 1) += lateral.y() * lateral.y();
    return c;
  }
};

// The paper's (sigma_X, sigma_Y, sigma_Z).
inline Eigen::Vector3d point_sigma(const Eigen::Vector3d& p, double depth_noise_coeff) {
  const double sz = depth_noise_coeff * p.z() * p.z();
  return {std::abs(p.x() / p.z()) * sz, std::abs(p.y() / p.z()) * sz, sz};
}

inline PointNoise paper_point_noise(const Eigen::Vector3d& p, double depth_noise_coeff) {
  const Eigen::Vector3d s = point_sigma(p, depth_noise_coeff);
  PointNoise n;
  n.lateral = s.head<2>();
  n.ray = {0, 0, s.z()};
  return n;
}

// The physical model's parameters (one home for each number: pipeline_config.hpp).
struct SensorNoise {
  double depth_noise_coeff = CovarianceConfig{}.depth_noise_coeff;  // sigma_Z = c Z^2
  double pixel_sigma_px = CovarianceConfig{}.pixel_sigma_px;        // keypoint error at level 0
  double level_scale = FeatureConfig{}.orb_scale_factor;            // pyramid scale per level
  double depth_lateral_sigma_px = CovarianceConfig{}.depth_lateral_sigma_px;
  double fx = CameraConfig{}.fx, fy = CameraConfig{}.fy;
  double depth_rounding_sigma_m = 1.0 / (DepthConfig{}.units_per_m * std::sqrt(12.0));  // one unit, uniform
};

inline SensorNoise sensor_noise(const PipelineConfig& c) {
  return {c.covariance.depth_noise_coeff, c.covariance.pixel_sigma_px, c.features.orb_scale_factor,
          c.covariance.depth_lateral_sigma_px, c.camera.fx, c.camera.fy,
          1.0 / (c.depth.units_per_m * std::sqrt(12.0))};
}

inline double keypoint_sigma_px(int level, const SensorNoise& noise) {
  return noise.pixel_sigma_px * std::pow(noise.level_scale, std::max(0, level));
}

// depth_gradient: dZ/du, dZ/dv in metres per pixel at the keypoint; sigma_px: the keypoint's
// localisation error at level-0 pixels.
inline PointNoise physical_point_noise_px(const Eigen::Vector3d& p, double sigma_px,
                                          const Eigen::Vector2d& depth_gradient, const SensorNoise& noise) {
  const double z = p.z();
  const double sp = sigma_px;
  const double axial = noise.depth_noise_coeff * z * z;
  const double rounding = noise.depth_rounding_sigma_m;
  const double slope2 = depth_gradient.squaredNorm();
  const double sl = noise.depth_lateral_sigma_px;
  PointNoise n;
  n.lateral = {sp * z / noise.fx, sp * z / noise.fy};
  n.ray = std::sqrt(axial * axial + rounding * rounding + slope2 * (sp * sp + sl * sl)) * (p / z);
  return n;
}

inline PointNoise physical_point_noise(const Eigen::Vector3d& p, int level, const Eigen::Vector2d& depth_gradient,
                                       const SensorNoise& noise) {
  return physical_point_noise_px(p, keypoint_sigma_px(level, noise), depth_gradient, noise);
}

// The model RANSAC's final fit weighs each point by: the sensor's constants as learnt so far
// (each level's keypoint localisation, pipeline/keypoint_sigma.hpp; the depth noise
// coefficient, DepthNoiseEstimate), the keypoint's error across the ray and through the
// depth's slope along it, without the depth map's lateral noise. Weights without the slope
// term collapse as the depth noise goes to zero; the depth map's lateral noise in the weights
// made the Kinect's pairs 1.5-4 % worse (fr1_xyz and its every-2nd/3rd-frame copies).
inline SensorNoise fit_weight_noise(SensorNoise noise) {
  noise.depth_lateral_sigma_px = 0;
  return noise;
}

// A learnt constant as the fit's weights take it: in steps of 2^(1/32) (2.2 %). A weight 2 %
// off changes no fit noticeably, and the same frames then give the same motions whatever the
// last bits of the estimates: pass after pass of a looped recording, and on another CPU's libm
// (the learnt state carries such differences from pair to pair and grew them to 5e-6 m in
// 39 pairs between the armhf and x86-64 builds).
inline double in_weight_steps(double x) {
  return x > 0 ? std::exp2(std::round(std::log2(x) * 32.0) / 32.0) : x;
}

// The 3x3 covariance of a point seen alone (level 0, no slope term): the final fit's weights
// where the caller gives none per point.
inline Eigen::Matrix3d point_covariance(const Eigen::Vector3d& p, const SensorNoise& noise) {
  return physical_point_noise(p, 0, Eigen::Vector2d::Zero(), noise).covariance();
}

// Weight of a correspondence in the covariance's least-squares refits: inverse of the paper
// model's total variance (the estimate's own RANSAC-stage weights).
inline double pair_weight(const Eigen::Vector3d& prev, const Eigen::Vector3d& curr, double depth_noise_coeff) {
  return 1.0 / (point_sigma(prev, depth_noise_coeff).squaredNorm() + point_sigma(curr, depth_noise_coeff).squaredNorm());
}

}  // namespace rgbdo
