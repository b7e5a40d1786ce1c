#pragma once
// Stage 5: the odometry covariance by statistical perturbation (Willis & Brink Sec. III-C).
// The inlier point pairs are perturbed N times with the sensor noise model, each perturbed
// pair of clouds is aligned again, and the unbiased sample covariance of the N parameter
// vectors xi = (t, rotation vector) is the estimate, multiplied by the configured scale.
#include <Eigen/Geometry>
#include <random>
#include <vector>

#include "rgbd_odometry/config.hpp"
#include "rgbd_odometry/geometry.hpp"

namespace rgbdo {

class PerturbationCovariance {
 public:
  explicit PerturbationCovariance(const CovarianceConfig& config) : config_(config) {}

  // prev[k] ~ T curr[k]; returns false when the result is not finite, symmetric, positive definite.
  [[nodiscard]] bool estimate(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                              std::mt19937_64& rng, Matrix6d& covariance);

 private:
  CovarianceConfig config_;
  std::vector<Eigen::Vector3d> noisy_prev_, noisy_curr_, sigma_prev_, sigma_curr_;
  std::vector<double> weights_;
  std::vector<Vector6d> samples_;
};

// Finite, symmetric and positive definite: what an estimator may safely invert.
bool is_valid_covariance(const Matrix6d& c);

}  // namespace rgbdo
