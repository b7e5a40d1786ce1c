#include "rgbd_odometry/pipeline/covariance.hpp"

#include <Eigen/Cholesky>
#include <algorithm>

#include "rgbd_odometry/core/noise_model.hpp"
#include "rgbd_odometry/core/umeyama.hpp"

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

PerturbationCovariance::PerturbationCovariance(const CovarianceConfig& config, int max_points)
    : config_(config),
      kernels_(simd::active_kernels()),
      padded_perturbations_((config.perturbations + simd::kPerturbationLanes - 1) / simd::kPerturbationLanes *
                            simd::kPerturbationLanes) {
  reserve(max_points);
  sums_.resize(static_cast<size_t>(15 * padded_perturbations_));
  samples_.reserve(static_cast<size_t>(config.perturbations));
}

void PerturbationCovariance::reserve(int points) {
  for (auto* v : {&sx_, &sy_, &sz_, &dx_, &dy_, &dz_, &ssx_, &ssy_, &ssz_, &sdx_, &sdy_, &sdz_, &w_})
    v->reserve(static_cast<size_t>(points));
  weights_.reserve(static_cast<size_t>(points));
}

bool PerturbationCovariance::estimate(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                                      const Eigen::Isometry3d& T_prev_curr, Rng& rng, Matrix6d& covariance) {
  const size_t n = prev.size();
  samples_.clear();
  if (n < 3 || curr.size() != n) return false;
  const double c = config_.depth_noise_coeff;

  // Centre both clouds on their weighted centroids (in double) so that the float sums hold
  // small numbers and the per-perturbation cross-covariance loses no precision.
  for (auto* v : {&sx_, &sy_, &sz_, &dx_, &dy_, &dz_, &ssx_, &ssy_, &ssz_, &sdx_, &sdy_, &sdz_, &w_}) v->resize(n);
  weights_.resize(n);
  double total = 0;
  Eigen::Vector3d centre_s = Eigen::Vector3d::Zero(), centre_d = Eigen::Vector3d::Zero();
  for (size_t k = 0; k < n; ++k) {
    const double w = pair_weight(prev[k], curr[k], c);  // the same weights as the fit's
    weights_[k] = w;
    total += w;
    centre_s += w * curr[k];
    centre_d += w * prev[k];
  }
  centre_s /= total;
  centre_d /= total;
  for (size_t k = 0; k < n; ++k) {
    const Eigen::Vector3d s = curr[k] - centre_s, d = prev[k] - centre_d;
    const Eigen::Vector3d sigma_s = point_sigma(curr[k], c), sigma_d = point_sigma(prev[k], c);
    sx_[k] = static_cast<float>(s.x());
    sy_[k] = static_cast<float>(s.y());
    sz_[k] = static_cast<float>(s.z());
    dx_[k] = static_cast<float>(d.x());
    dy_[k] = static_cast<float>(d.y());
    dz_[k] = static_cast<float>(d.z());
    ssx_[k] = static_cast<float>(sigma_s.x());
    ssy_[k] = static_cast<float>(sigma_s.y());
    ssz_[k] = static_cast<float>(sigma_s.z());
    sdx_[k] = static_cast<float>(sigma_d.x());
    sdy_[k] = static_cast<float>(sigma_d.y());
    sdz_[k] = static_cast<float>(sigma_d.z());
    w_[k] = static_cast<float>(weights_[k] / total);
  }

  simd::PerturbationInput in;
  in.points = static_cast<int>(n);
  in.perturbations = padded_perturbations_;
  in.sx = sx_.data(), in.sy = sy_.data(), in.sz = sz_.data();
  in.dx = dx_.data(), in.dy = dy_.data(), in.dz = dz_.data();
  in.sigma_sx = ssx_.data(), in.sigma_sy = ssy_.data(), in.sigma_sz = ssz_.data();
  in.sigma_dx = sdx_.data(), in.sigma_dy = sdy_.data(), in.sigma_dz = sdz_.data();
  in.w = w_.data();
  in.seed = (static_cast<std::uint64_t>(rng.next_u32()) << 32) | rng.next_u32();
  simd::PerturbationSums out;
  const size_t P = static_cast<size_t>(padded_perturbations_);
  for (int j = 0; j < 3; ++j) {
    out.s[j] = sums_.data() + static_cast<size_t>(j) * P;
    out.d[j] = sums_.data() + static_cast<size_t>(3 + j) * P;
  }
  for (int e = 0; e < 9; ++e) out.m[e] = sums_.data() + static_cast<size_t>(6 + e) * P;
  kernels_.perturbation_sums(in, out);

  double weight_sum = 0;  // of the float weights actually used, in double
  for (size_t k = 0; k < n; ++k) weight_sum += w_[k];
  for (int p = 0; p < config_.perturbations; ++p) {
    Eigen::Vector3d s, d;
    Eigen::Matrix3d m;
    for (int j = 0; j < 3; ++j) {
      s(j) = out.s[j][p];
      d(j) = out.d[j][p];
    }
    for (int e = 0; e < 9; ++e) m(e / 3, e % 3) = out.m[e][p];
    Eigen::Isometry3d T;  // maps centred current points onto centred previous ones
    if (!fit_from_sums(s, d, m, weight_sum, T)) return false;
    T.translation() += centre_d - T.linear() * centre_s;
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
