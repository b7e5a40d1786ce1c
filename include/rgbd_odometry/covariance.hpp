#pragma once
// Stage 5: the odometry covariance by statistical perturbation (Willis & Brink Sec. III-C).
// The inlier point pairs are perturbed N times with the sensor noise model, each perturbed
// pair of clouds is aligned again, and the unbiased sample covariance of the N parameter
// vectors xi = (t, rotation vector) is the estimate, multiplied by the configured scale.
//
// The noise model is a lower bound: real keypoints are off by more than it predicts
// (localisation, depth quantisation, registration). With `residual_variance_factor` the
// sample covariance is also multiplied by the a-posteriori variance factor of the fit,
//   s0^2 = sum_k w_k |prev_k - T curr_k|^2 / (n - 2),  floored at 1,
// the least-squares estimate of how much noisier this pair's points are than modelled:
// a pair with sloppy inliers then reports a proportionally larger covariance.
#include <Eigen/Geometry>
#include <vector>

#include "rgbd_odometry/config.hpp"
#include "rgbd_odometry/geometry.hpp"
#include "rgbd_odometry/rng.hpp"

namespace rgbdo {

class PerturbationCovariance {
 public:
  explicit PerturbationCovariance(const CovarianceConfig& config) : config_(config) {}

  // prev[k] ~ T curr[k] (the inliers and the fitted motion); returns false when the result
  // is not finite, symmetric and positive definite.
  [[nodiscard]] bool estimate(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                              const Eigen::Isometry3d& T_prev_curr, Rng& rng, Matrix6d& covariance);

  // s0^2 of the fit (>= 1), as described above.
  static double variance_factor(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                                const Eigen::Isometry3d& T_prev_curr, double depth_noise_coeff);

 private:
  CovarianceConfig config_;
  std::vector<Eigen::Vector3d> noisy_prev_, noisy_curr_, sigma_prev_, sigma_curr_;
  std::vector<double> weights_;
  std::vector<Vector6d> samples_;
};

// Finite, symmetric and positive definite: what an estimator may safely invert.
bool is_valid_covariance(const Matrix6d& c);

}  // namespace rgbdo
