#pragma once
// The depth sensor's measurement noise (Willis & Brink eq. 2, after Khoshelham & Elberink):
//   sigma_Z = c Z^2,  sigma_X = |X/Z| sigma_Z,  sigma_Y = |Y/Z| sigma_Z,  c = 1.425e-3 / m.
// point_sigma() is that model, used to perturb points for the covariance as the paper does.
// point_covariance() is its physical form for the final fit: a depth error moves the point
// along its viewing ray m = P / Z (so X, Y, Z errors are fully correlated), and the
// keypoint's pixel error moves it across the ray.
#include <Eigen/Core>
#include <cmath>

#include "rgbd_odometry/core/config.hpp"

namespace rgbdo {

inline Eigen::Vector3d point_sigma(const Eigen::Vector3d& p, double depth_noise_coeff) {
  const double sz = depth_noise_coeff * p.z() * p.z();
  return {std::abs(p.x() / p.z()) * sz, std::abs(p.y() / p.z()) * sz, sz};
}

// Weight of a correspondence in a least-squares fit: inverse of its total expected variance.
inline double pair_weight(const Eigen::Vector3d& prev, const Eigen::Vector3d& curr, double depth_noise_coeff) {
  return 1.0 / (point_sigma(prev, depth_noise_coeff).squaredNorm() + point_sigma(curr, depth_noise_coeff).squaredNorm());
}

// The noise of one camera's measurements. Its defaults are the configuration's (one home for
// each number: config.hpp); sensor_noise() takes a loaded configuration's.
struct SensorNoise {
  double depth_noise_coeff = CovarianceConfig{}.depth_noise_coeff;  // sigma_Z = c Z^2
  double pixel_sigma_px = CovarianceConfig{}.pixel_sigma_px;        // keypoint localisation error
  double focal_px = CameraConfig{}.fx;
};

inline SensorNoise sensor_noise(const Config& c) {
  return {c.covariance.depth_noise_coeff, c.covariance.pixel_sigma_px, c.camera.fx};
}

inline Eigen::Matrix3d point_covariance(const Eigen::Vector3d& p, const SensorNoise& noise) {
  const double z = p.z();
  const double sz = noise.depth_noise_coeff * z * z;
  const double sl = noise.pixel_sigma_px * z / noise.focal_px;
  const Eigen::Vector3d ray = p / z;
  Eigen::Matrix3d c = sz * sz * ray * ray.transpose();
  c(0, 0) += sl * sl;
  c(1, 1) += sl * sl;
  return c;
}

}  // namespace rgbdo
