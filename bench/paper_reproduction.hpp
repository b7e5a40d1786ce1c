#pragma once
// The obvious implementation of Willis & Brink's pipeline with the libraries at hand: what a
// straightforward reproduction of the paper does per frame, measured beside the project's
// pipeline in one run (bench_pipeline) so that the speed-up is a ratio, not a claim:
//   mask           cv::inRange on the depth, periphery zeroed
//   features       OpenCV's ORB (1000 features, 8 levels x 1.2, FAST 20)
//   matching       cv::BFMatcher(NORM_HAMMING).knnMatch(k = 2) both ways, ratio test, mutual
//   3-D points     cv::undistortPoints, depth at the keypoint
//   RANSAC         the project's first, straightforward RANSAC (straightforward_ransac.hpp)
//   covariance     std::normal_distribution noise and Eigen::umeyama per perturbation
#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <random>
#include <vector>

#include "straightforward_ransac.hpp"
#include "rgbd_odometry/app/config.hpp"
#include "rgbd_odometry/core/geometry.hpp"
#include "rgbd_odometry/pipeline/noise_model.hpp"
#include "rgbd_odometry/pipeline/frame.hpp"

namespace rgbdo {

// 100 perturbations of the inlier clouds, each fitted by Eigen::umeyama: the covariance of
// the motion parameters (t, rotation vector), as the paper computes it.
inline Matrix6d straightforward_covariance(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                                           double depth_noise_coeff, int perturbations, std::mt19937_64& rng) {
  const auto n = static_cast<Eigen::Index>(prev.size());
  Eigen::Matrix3Xd src(3, n), dst(3, n), sigma_src(3, n), sigma_dst(3, n);
  for (Eigen::Index k = 0; k < n; ++k) {
    src.col(k) = curr[static_cast<size_t>(k)];
    dst.col(k) = prev[static_cast<size_t>(k)];
    sigma_src.col(k) = point_sigma(curr[static_cast<size_t>(k)], depth_noise_coeff);
    sigma_dst.col(k) = point_sigma(prev[static_cast<size_t>(k)], depth_noise_coeff);
  }
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<Vector6d> xs;
  for (int p = 0; p < perturbations; ++p) {
    Eigen::Matrix3Xd noisy_src = src, noisy_dst = dst;
    for (Eigen::Index k = 0; k < n; ++k)
      for (int c = 0; c < 3; ++c) {
        noisy_src(c, k) += sigma_src(c, k) * gauss(rng);
        noisy_dst(c, k) += sigma_dst(c, k) * gauss(rng);
      }
    const Eigen::Matrix4d T = Eigen::umeyama(noisy_src, noisy_dst, false);
    Vector6d xi;
    xi.head<3>() = T.topRightCorner<3, 1>();
    const Eigen::AngleAxisd aa(Eigen::Matrix3d(T.topLeftCorner<3, 3>()));
    xi.tail<3>() = aa.axis() * aa.angle();
    xs.push_back(xi);
  }
  return sample_covariance(xs);
}

class PaperReproduction {
 public:
  explicit PaperReproduction(const Config& config)
      : config_(config),
        orb_(cv::ORB::create(1000, 1.2f, 8, 31, 0, 2, cv::ORB::HARRIS_SCORE, 31, 20)),
        matcher_(cv::NORM_HAMMING),
        ransac_(config.ransac, sensor_noise(config)),
        camera_((cv::Mat_<double>(3, 3) << config.camera.fx, 0, config.camera.cx, 0, config.camera.fy, config.camera.cy, 0, 0, 1)),
        distortion_(cv::Mat(config.camera.distortion).clone()) {}

  // One frame against the previous one: false for the first frame or a failed pair.
  bool process(const RgbdFrame& frame, Eigen::Isometry3d& motion, Matrix6d& covariance) {
    cv::Mat mask;
    cv::inRange(frame.depth_m, config_.depth.min_m, config_.depth.max_m, mask);
    const int b = config_.features.border_px;
    mask.rowRange(0, b).setTo(0), mask.rowRange(mask.rows - b, mask.rows).setTo(0);
    mask.colRange(0, b).setTo(0), mask.colRange(mask.cols - b, mask.cols).setTo(0);
    Frame current;
    orb_->detectAndCompute(frame.gray, mask, current.keypoints, current.descriptors);
    current.points = back_project(current.keypoints, frame.depth_m);
    const bool ok = !previous_.keypoints.empty() && solve(previous_, current, motion, covariance);
    previous_ = std::move(current);
    return ok;
  }

 private:
  struct Frame {
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat descriptors;
    std::vector<Eigen::Vector3d> points;  // z = 0: no depth
  };

  bool solve(const Frame& prev, const Frame& curr, Eigen::Isometry3d& motion, Matrix6d& covariance) {
    std::vector<std::vector<cv::DMatch>> forward, backward;
    matcher_.knnMatch(prev.descriptors, curr.descriptors, forward, 2);
    matcher_.knnMatch(curr.descriptors, prev.descriptors, backward, 2);
    const auto distinct = [&](const std::vector<cv::DMatch>& m) {
      return !m.empty() && (m.size() < 2 || m[0].distance < config_.matching.ratio * m[1].distance);
    };
    std::vector<Eigen::Vector3d> prev_points, curr_points;
    for (const auto& f : forward) {
      if (!distinct(f)) continue;
      const auto& back = backward[static_cast<size_t>(f[0].trainIdx)];
      if (!distinct(back) || back[0].trainIdx != f[0].queryIdx) continue;
      const Eigen::Vector3d& p = prev.points[static_cast<size_t>(f[0].queryIdx)];
      const Eigen::Vector3d& q = curr.points[static_cast<size_t>(f[0].trainIdx)];
      if (p.z() <= 0 || q.z() <= 0) continue;
      prev_points.push_back(p);
      curr_points.push_back(q);
    }
    if (static_cast<int>(prev_points.size()) < config_.ransac.min_inliers) return false;
    Rng rng(++pairs_);
    const StraightforwardResult fit = ransac_.estimate(prev_points, curr_points, rng);
    if (fit.status != Status::Ok) return false;
    std::vector<Eigen::Vector3d> inlier_prev, inlier_curr;
    for (int k : fit.inliers) {
      inlier_prev.push_back(prev_points[static_cast<size_t>(k)]);
      inlier_curr.push_back(curr_points[static_cast<size_t>(k)]);
    }
    motion = fit.T_prev_curr;
    covariance = straightforward_covariance(inlier_prev, inlier_curr, config_.covariance.depth_noise_coeff,
                                            config_.covariance.perturbations, noise_);
    return true;
  }

  std::vector<Eigen::Vector3d> back_project(const std::vector<cv::KeyPoint>& keypoints, const cv::Mat& depth_m) const {
    std::vector<cv::Point2f> pixels, normalised;
    for (const auto& k : keypoints) pixels.push_back(k.pt);
    if (!pixels.empty()) cv::undistortPoints(pixels, normalised, camera_, distortion_);
    std::vector<Eigen::Vector3d> points;
    for (size_t i = 0; i < keypoints.size(); ++i) {
      const double z = depth_m.at<float>(cvRound(keypoints[i].pt.y), cvRound(keypoints[i].pt.x));
      points.emplace_back(normalised[i].x * z, normalised[i].y * z, z);
    }
    return points;
  }

  Config config_;
  cv::Ptr<cv::ORB> orb_;
  cv::BFMatcher matcher_;
  StraightforwardRansac ransac_;
  cv::Mat camera_, distortion_;
  Frame previous_;
  std::uint64_t pairs_ = 0;
  std::mt19937_64 noise_{1};
};

}  // namespace rgbdo
