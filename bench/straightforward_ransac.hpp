#pragma once
// The project's first, straightforward RANSAC, kept as the paper reproduction's
// (paper_reproduction.hpp): the obvious alternative the benchmarks measure the allocation-free
// one against. std::vector results, fit_rigid (SVD) on every triplet, double-precision
// scoring of Eigen vectors. The tests check RigidRansac against an oracle of their own
// (test/ransac_oracle.hpp), not against this.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <vector>

#include "rgbd_odometry/app/config.hpp"
#include "rgbd_odometry/pipeline/noise_model.hpp"
#include "rgbd_odometry/core/rng.hpp"
#include "rgbd_odometry/core/status.hpp"
#include "rgbd_odometry/core/umeyama.hpp"

namespace rgbdo {

struct StraightforwardResult {
  Status status = Status::RansacFailed;
  Eigen::Isometry3d T_prev_curr = Eigen::Isometry3d::Identity();  // maps curr points into prev
  std::vector<int> inliers;  // indices into the point pairs
  double threshold_m = 0;    // the final (refined) inlier threshold
  int hypotheses = 0;        // non-degenerate samples scored
};

class StraightforwardRansac {
 public:
  StraightforwardRansac(const RansacConfig& ransac, const SensorNoise& noise);

  // prev[k] ~ T * curr[k] for inliers k.
  [[nodiscard]] StraightforwardResult estimate(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                                      Rng& rng);

  // The refinement alone, from a given motion (used again after the points were corrected).
  [[nodiscard]] StraightforwardResult refine(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                                    const Eigen::Isometry3d& initial);

 private:
  bool sample_is_degenerate(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                            const int* idx) const;
  // Gauss-Newton on sum_k r_k^T (C_prev + R C_curr R^T)^-1 r_k over the inliers, from T.
  Eigen::Isometry3d fit_anisotropic(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                                    const std::vector<int>& inliers, Eigen::Isometry3d T) const;
  RansacConfig config_;
  SensorNoise noise_;
  std::vector<int> scratch_inliers_;
  std::vector<Eigen::Vector3d> fit_prev_, fit_curr_;
  std::vector<double> fit_weights_;
};

namespace straightforward_detail {

constexpr int kMaxRefinements = 20;
constexpr double kSuccessProbability = 0.999;  // adaptive stop once a clean sample is this likely
constexpr double kMinSampleSide_m = 0.02;      // shorter triangle sides barely constrain rotation
constexpr double kMinSampleSine = 0.1;         // ~6 degrees: flatter triangles are near-collinear
constexpr double kMaxRefinementRotation_rad = 0.05;

}  // namespace straightforward_detail
using namespace straightforward_detail;

inline StraightforwardRansac::StraightforwardRansac(const RansacConfig& ransac, const SensorNoise& noise)
    : config_(ransac), noise_(noise) {}

inline Eigen::Isometry3d StraightforwardRansac::fit_anisotropic(const std::vector<Eigen::Vector3d>& prev,
                                               const std::vector<Eigen::Vector3d>& curr,
                                               const std::vector<int>& inliers, Eigen::Isometry3d T) const {
  constexpr int kIterations = 5;
  using Matrix6d = Eigen::Matrix<double, 6, 6>;
  using Vector6d = Eigen::Matrix<double, 6, 1>;
  for (int it = 0; it < kIterations; ++it) {
    Matrix6d H = Matrix6d::Zero();
    Vector6d g = Vector6d::Zero();
    for (int k : inliers) {
      const Eigen::Vector3d& p = prev[static_cast<size_t>(k)];
      const Eigen::Vector3d y = T * curr[static_cast<size_t>(k)];
      const Eigen::Vector3d r = p - y;
      const Eigen::Matrix3d C = point_covariance(p, noise_) +
                                T.linear() * point_covariance(curr[static_cast<size_t>(k)], noise_) * T.linear().transpose();
      const Eigen::Matrix3d W = C.inverse();
      // r(delta) = p - exp(delta) y ~ r - dt + [y]x dw  =>  J = [-I, [y]x]
      Eigen::Matrix<double, 3, 6> J;
      J.leftCols<3>() = -Eigen::Matrix3d::Identity();
      J.rightCols<3>() << 0, -y.z(), y.y(), y.z(), 0, -y.x(), -y.y(), y.x(), 0;
      H += J.transpose() * W * J;
      g += J.transpose() * W * r;
    }
    const Vector6d delta = -H.ldlt().solve(g);
    if (!delta.allFinite()) break;
    Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
    const double angle = delta.tail<3>().norm();
    if (angle > 0) step.linear() = Eigen::AngleAxisd(angle, delta.tail<3>() / angle).toRotationMatrix();
    step.translation() = delta.head<3>();
    T = step * T;
    if (delta.norm() < 1e-10) break;
  }
  return T;
}

inline bool StraightforwardRansac::sample_is_degenerate(const std::vector<Eigen::Vector3d>& prev,
                                       const std::vector<Eigen::Vector3d>& curr, const int* idx) const {
  for (const auto* cloud : {&prev, &curr}) {
    const Eigen::Vector3d& a = (*cloud)[static_cast<size_t>(idx[0])];
    const Eigen::Vector3d ab = (*cloud)[static_cast<size_t>(idx[1])] - a;
    const Eigen::Vector3d ac = (*cloud)[static_cast<size_t>(idx[2])] - a;
    const double lab = ab.norm(), lac = ac.norm();
    if (lab < kMinSampleSide_m || lac < kMinSampleSide_m) return true;
    if (ab.cross(ac).norm() < kMinSampleSine * lab * lac) return true;
  }
  // A rigid motion keeps distances: a sample that stretches a side by more than twice the
  // inlier threshold holds an outlier, and need not be solved.
  for (int e = 0; e < 3; ++e) {
    const auto i = static_cast<size_t>(idx[e]), j = static_cast<size_t>(idx[(e + 1) % 3]);
    if (std::abs((prev[i] - prev[j]).norm() - (curr[i] - curr[j]).norm()) > 2 * config_.inlier_threshold_m) return true;
  }
  return false;
}

inline StraightforwardResult StraightforwardRansac::estimate(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                                   Rng& rng) {
  StraightforwardResult result;
  const int n = static_cast<int>(prev.size());
  if (n < std::max(3, config_.min_inliers)) return result;

  const double threshold_sq = config_.inlier_threshold_m * config_.inlier_threshold_m;
  int best_count = -1;
  double best_cost = 0;
  Eigen::Isometry3d best = Eigen::Isometry3d::Identity();
  int needed = config_.max_iterations;
  // Degenerate draws are cheap and do not count as hypotheses, but are bounded too.
  const int max_draws = 10 * config_.max_iterations;
  for (int draw = 0; draw < max_draws && result.hypotheses < needed; ++draw) {
    const auto un = static_cast<std::uint32_t>(n);
    const int idx[3] = {static_cast<int>(rng.below(un)), static_cast<int>(rng.below(un)), static_cast<int>(rng.below(un))};
    if (idx[0] == idx[1] || idx[0] == idx[2] || idx[1] == idx[2]) continue;
    if (sample_is_degenerate(prev, curr, idx)) continue;
    const Eigen::Vector3d s[3] = {curr[static_cast<size_t>(idx[0])], curr[static_cast<size_t>(idx[1])],
                                  curr[static_cast<size_t>(idx[2])]};
    const Eigen::Vector3d d[3] = {prev[static_cast<size_t>(idx[0])], prev[static_cast<size_t>(idx[1])],
                                  prev[static_cast<size_t>(idx[2])]};
    Eigen::Isometry3d T;
    if (!fit_rigid(s, d, {}, T)) continue;
    ++result.hypotheses;

    // Score: inlier count, ties broken by the truncated squared error (MSAC's cost).
    int count = 0;
    double cost = 0;
    for (int k = 0; k < n; ++k) {
      const double e = (prev[static_cast<size_t>(k)] - T * curr[static_cast<size_t>(k)]).squaredNorm();
      if (e < threshold_sq) {
        ++count;
        cost += e;
      } else {
        cost += threshold_sq;
      }
    }
    if (count > best_count || (count == best_count && cost < best_cost)) {
      best_count = count;
      best_cost = cost;
      best = T;
      const double w = static_cast<double>(count) / n;
      const double p_fail = 1.0 - w * w * w;
      if (p_fail <= 1e-12) {
        needed = result.hypotheses;
      } else {
        const double k = std::log(1.0 - kSuccessProbability) / std::log(p_fail);
        needed = std::min(config_.max_iterations, static_cast<int>(std::ceil(k)));
      }
    }
  }
  if (best_count < 0) {
    result.status = Status::DegenerateSample;
    return result;
  }
  const int hypotheses = result.hypotheses;
  result = refine(prev, curr, best);
  result.hypotheses = hypotheses;
  return result;
}

inline StraightforwardResult StraightforwardRansac::refine(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                                 const Eigen::Isometry3d& initial) {
  StraightforwardResult result;
  result.T_prev_curr = initial;
  const size_t n = prev.size();
  double threshold = config_.inlier_threshold_m;
  std::vector<int>& inliers = result.inliers;
  for (int round = 0; round < kMaxRefinements; ++round) {
    scratch_inliers_.clear();
    for (size_t k = 0; k < n; ++k)
      if ((prev[k] - result.T_prev_curr * curr[k]).norm() < threshold) scratch_inliers_.push_back(static_cast<int>(k));
    if (scratch_inliers_.size() < 3) break;
    const bool stable = scratch_inliers_ == inliers;
    inliers.swap(scratch_inliers_);
    if (stable) break;

    fit_prev_.clear();
    fit_curr_.clear();
    fit_weights_.clear();
    for (int k : inliers) {
      fit_prev_.push_back(prev[static_cast<size_t>(k)]);
      fit_curr_.push_back(curr[static_cast<size_t>(k)]);
      fit_weights_.push_back(pair_weight(fit_prev_.back(), fit_curr_.back(), noise_.depth_noise_coeff));
    }
    Eigen::Isometry3d T;
    if (!fit_rigid(fit_curr_, fit_prev_, fit_weights_, T)) break;
    result.T_prev_curr = T;
    if (!config_.refine_threshold) continue;
    double sum_sq = 0;
    for (size_t k = 0; k < fit_prev_.size(); ++k) sum_sq += (fit_prev_[k] - T * fit_curr_[k]).squaredNorm();
    const double sigma = std::sqrt(sum_sq / static_cast<double>(fit_prev_.size()));
    threshold = std::min(3 * sigma, config_.inlier_threshold_m);
  }
  result.threshold_m = threshold;
  if (inliers.size() >= 3) {
    const Eigen::Isometry3d refined = fit_anisotropic(prev, curr, inliers, result.T_prev_curr);
    // The refinement corrects the least-squares fit by noise-level amounts. A jump of more
    // than the inlier threshold means a near-degenerate geometry: keep the plain fit.
    const Eigen::Isometry3d change = result.T_prev_curr.inverse() * refined;
    if (refined.matrix().allFinite() && change.translation().norm() < config_.inlier_threshold_m &&
        Eigen::AngleAxisd(change.linear()).angle() < kMaxRefinementRotation_rad)
      result.T_prev_curr = refined;
  }
  result.status = static_cast<int>(inliers.size()) >= config_.min_inliers ? Status::Ok : Status::RansacFailed;
  return result;
}

}  // namespace rgbdo
