#include "rgbd_odometry/covariance.hpp"

#include <Eigen/Cholesky>
#include <algorithm>

#include "rgbd_odometry/noise_model.hpp"
#include "rgbd_odometry/umeyama.hpp"

namespace rgbdo {

bool is_valid_covariance(const Matrix6d& c) {
  if (!c.allFinite()) return false;
  if (!c.isApprox(c.transpose(), 1e-9)) return false;
  const Eigen::LLT<Matrix6d> llt(c);
  return llt.info() == Eigen::Success;
}

double PerturbationCovariance::variance_factor(const std::vector<Eigen::Vector3d>& prev,
                                               const std::vector<Eigen::Vector3d>& curr,
                                               const Eigen::Isometry3d& T_prev_curr, double depth_noise_coeff) {
  const size_t n = prev.size();
  if (n < 3) return 1.0;
  double sum = 0;
  for (size_t k = 0; k < n; ++k)
    sum += pair_weight(prev[k], curr[k], depth_noise_coeff) * (prev[k] - T_prev_curr * curr[k]).squaredNorm();
  // 3n residual components, 6 parameters; each weighted residual carries 3 components.
  return std::max(1.0, sum / (static_cast<double>(n) - 2.0));
}

bool PerturbationCovariance::estimate(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                                      const Eigen::Isometry3d& T_prev_curr, Rng& rng,
                                      Matrix6d& covariance) {
  const size_t n = prev.size();
  const double c = config_.depth_noise_coeff;
  sigma_prev_.resize(n);
  sigma_curr_.resize(n);
  weights_.resize(n);
  for (size_t k = 0; k < n; ++k) {
    sigma_prev_[k] = point_sigma(prev[k], c);
    sigma_curr_[k] = point_sigma(curr[k], c);
    weights_[k] = pair_weight(prev[k], curr[k], c);  // the same weights as the estimate's own fit
  }
  noisy_prev_.resize(n);
  noisy_curr_.resize(n);
  samples_.clear();
  for (int s = 0; s < config_.perturbations; ++s) {
    for (size_t k = 0; k < n; ++k) {
      // Named draws: the order of the three normals must not depend on evaluation order.
      const double a = rng.gaussian(), b = rng.gaussian(), c3 = rng.gaussian();
      noisy_prev_[k] = prev[k] + sigma_prev_[k].cwiseProduct(Eigen::Vector3d(a, b, c3));
      const double d = rng.gaussian(), e = rng.gaussian(), f = rng.gaussian();
      noisy_curr_[k] = curr[k] + sigma_curr_[k].cwiseProduct(Eigen::Vector3d(d, e, f));
    }
    Eigen::Isometry3d T;
    if (!fit_rigid(noisy_curr_, noisy_prev_, weights_, T)) return false;
    samples_.push_back(xi_from_transform(T));
  }
  Vector6d mean = Vector6d::Zero();
  for (const auto& x : samples_) mean += x;
  mean /= static_cast<double>(samples_.size());
  covariance.setZero();
  for (const auto& x : samples_) covariance += (x - mean) * (x - mean).transpose();
  double factor = config_.scale;
  if (config_.residual_variance_factor) factor *= variance_factor(prev, curr, T_prev_curr, c);
  covariance *= factor / static_cast<double>(samples_.size() - 1);
  covariance = 0.5 * (covariance + covariance.transpose());  // exact symmetry for consumers
  return is_valid_covariance(covariance);
}

}  // namespace rgbdo
