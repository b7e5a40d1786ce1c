#include "rgbd_odometry/pipeline/ransac.hpp"

#include <algorithm>
#include <cmath>

#include "rgbd_odometry/simd/kernels.hpp"
#include "rgbd_odometry/core/geometry.hpp"
#include "rgbd_odometry/pipeline/noise_model.hpp"
#include "rgbd_odometry/core/umeyama.hpp"

namespace rgbdo {
namespace {

constexpr int kMaxRefinements = 20;
constexpr double kSuccessProbability = 0.999;  // adaptive stop once a clean sample is this likely
constexpr double kMinSampleSide_m = 0.02;      // shorter triangle sides barely constrain rotation
constexpr double kMinSampleSine = 0.1;         // ~6 degrees: flatter triangles are near-collinear
constexpr double kMaxRefinementRotation_rad = 0.05;
// sqrt of chi^2(3)'s 99 % point: a Gaussian point pair is weighed in full 99 times in 100.
constexpr double kHuberMahalanobis = 3.368;

// Whether the sample idx[0..2] cannot give a motion worth scoring (see draw_sample).
bool sample_is_degenerate(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                          const int* idx, double inlier_threshold_m) {
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
    if (std::abs((prev[i] - prev[j]).norm() - (curr[i] - curr[j]).norm()) > 2 * inlier_threshold_m) return true;
  }
  return false;
}

}  // namespace

int adaptive_hypotheses(int inliers, int pairs, int cap) {
  const double w = pairs > 0 ? static_cast<double>(inliers) / pairs : 0.0;
  const double p_fail = 1.0 - w * w * w;
  if (p_fail <= 1e-12) return 1;
  // With no inlier yet (a best hypothesis that fits not even its own sample, as a frame pair
  // of pure mismatches gives) log(p_fail) is 0 and the ratio infinite: draw them all.
  if (!(p_fail < 1.0)) return cap;
  const double k = std::log(1.0 - kSuccessProbability) / std::log(p_fail);
  return k < cap ? static_cast<int>(std::ceil(k)) : cap;
}

RigidRansac::RigidRansac(const RansacConfig& ransac, const SensorNoise& noise, int capacity)
    : config_(ransac), noise_(noise), score_(simd::active_kernels().score_rigid) {
  const auto n = static_cast<size_t>(capacity);
  for (auto* v : {&px_, &py_, &pz_, &cx_, &cy_, &cz_}) v->reserve(n);
  fit_weights_.reserve(n);
  scratch_inliers_.reserve(n);
  fit_prev_.reserve(n);
  fit_curr_.reserve(n);
}

void RigidRansac::load(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr) {
  const size_t n = prev.size();
  for (auto* v : {&px_, &py_, &pz_, &cx_, &cy_, &cz_}) v->resize(n);
  for (size_t k = 0; k < n; ++k) {
    px_[k] = static_cast<float>(prev[k].x()), py_[k] = static_cast<float>(prev[k].y()), pz_[k] = static_cast<float>(prev[k].z());
    cx_[k] = static_cast<float>(curr[k].x()), cy_[k] = static_cast<float>(curr[k].y()), cz_[k] = static_cast<float>(curr[k].z());
  }
}

void RigidRansac::select_inliers(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                                 const Eigen::Isometry3d& T, double threshold, std::vector<int>& out) const {
  out.clear();
  for (size_t k = 0; k < prev.size(); ++k)
    if ((prev[k] - T * curr[k]).norm() < threshold) out.push_back(static_cast<int>(k));
}

Eigen::Isometry3d RigidRansac::fit_anisotropic(const std::vector<Eigen::Vector3d>& prev,
                                               const std::vector<Eigen::Vector3d>& curr,
                                               const std::vector<int>& inliers,
                                               const PointPairCovariances* covariances, Eigen::Isometry3d T) const {
  const bool own = covariances != nullptr && covariances->prev.size() == prev.size() &&
                   covariances->curr.size() == curr.size();
  constexpr int kIterations = 5;
  using Matrix6d = Eigen::Matrix<double, 6, 6>;
  using Vector6d = Eigen::Matrix<double, 6, 1>;
  for (int it = 0; it < kIterations; ++it) {
    Matrix6d H = Matrix6d::Zero();
    Vector6d g = Vector6d::Zero();
    for (int k : inliers) {
      const auto i = static_cast<size_t>(k);
      const Eigen::Vector3d& p = prev[i];
      const Eigen::Vector3d y = T * curr[i];
      const Eigen::Vector3d r = p - y;
      const Eigen::Matrix3d C = own ? Eigen::Matrix3d(covariances->prev[i] + T.linear() * covariances->curr[i] * T.linear().transpose())
                                    : Eigen::Matrix3d(point_covariance(p, noise_) +
                                                      T.linear() * point_covariance(curr[i], noise_) * T.linear().transpose());
      Eigen::Matrix3d W = C.inverse();
      Eigen::Vector3d Wr = W * r;
      if (own) {
        // Huber on the Mahalanobis distance: a point the model calls exact but whose residual
        // says otherwise (a corner's depth, the one bad match the threshold let in) pulls
        // with a bounded force instead of dominating the fit. (Squared first: most points are
        // within, and need no square root.)
        const double distance2 = r.dot(Wr);
        if (distance2 > kHuberMahalanobis * kHuberMahalanobis) {
          const double down = kHuberMahalanobis / std::sqrt(distance2);
          W *= down;
          Wr *= down;
        }
      }
      // r(delta) = p - exp(delta) y ~ r - dt + [y]x dw  =>  J = [-I, [y]x]
      Eigen::Matrix<double, 3, 6> J;
      J.leftCols<3>() = -Eigen::Matrix3d::Identity();
      J.rightCols<3>() = skew(y);
      H += J.transpose() * W * J;
      g += J.transpose() * Wr;
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

bool draw_sample(Rng& rng, const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                 double inlier_threshold_m, Eigen::Vector3d s[3], Eigen::Vector3d d[3]) {
  const auto n = static_cast<std::uint32_t>(prev.size());
  const int idx[3] = {static_cast<int>(rng.below(n)), static_cast<int>(rng.below(n)), static_cast<int>(rng.below(n))};
  if (idx[0] == idx[1] || idx[0] == idx[2] || idx[1] == idx[2]) return false;
  if (sample_is_degenerate(prev, curr, idx, inlier_threshold_m)) return false;
  for (int e = 0; e < 3; ++e) {
    s[e] = curr[static_cast<size_t>(idx[e])];
    d[e] = prev[static_cast<size_t>(idx[e])];
  }
  return true;
}

void RigidRansac::estimate(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr, Rng& rng,
                           RansacResult& result, const PointPairCovariances* covariances) {
  result.status = Status::RansacFailed;
  result.T_prev_curr = Eigen::Isometry3d::Identity();
  result.inliers.clear();
  result.threshold_m = 0;
  result.hypotheses = 0;
  if (static_cast<int>(prev.size()) < std::max(3, config_.min_inliers)) return;
  Eigen::Isometry3d best;
  const int hypotheses = sample_hypotheses(prev, curr, rng, best);
  if (hypotheses == 0) {
    result.status = Status::DegenerateSample;
    return;
  }
  refine(prev, curr, best, result, covariances);
  result.hypotheses = hypotheses;
}

int RigidRansac::sample_hypotheses(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                                   Rng& rng, Eigen::Isometry3d& best) {
  const int n = static_cast<int>(prev.size());
  if (n < 3) return 0;
  load(prev, curr);
  simd::RigidScoreInput in;
  in.n = n;
  in.px = px_.data(), in.py = py_.data(), in.pz = pz_.data();
  in.cx = cx_.data(), in.cy = cy_.data(), in.cz = cz_.data();
  in.threshold_sq = static_cast<float>(config_.inlier_threshold_m * config_.inlier_threshold_m);

  int hypotheses = 0, best_count = -1;
  float best_cost = 0;
  best = Eigen::Isometry3d::Identity();
  int needed = config_.max_iterations;
  // Degenerate draws are cheap and do not count as hypotheses, but are bounded too.
  const int max_draws = 10 * config_.max_iterations;
  for (int draw = 0; draw < max_draws && hypotheses < needed; ++draw) {
    Eigen::Vector3d s[3], d[3];
    if (!draw_sample(rng, prev, curr, config_.inlier_threshold_m, s, d)) continue;
    Eigen::Isometry3d T;
    if (!fit_triplet(s, d, T)) continue;
    ++hypotheses;

    // Score: inlier count, ties broken by the truncated squared error (MSAC's cost).
    for (int e = 0; e < 9; ++e) in.r[e] = static_cast<float>(T.linear()(e / 3, e % 3));
    for (int e = 0; e < 3; ++e) in.t[e] = static_cast<float>(T.translation()(e));
    int count = 0;
    float cost = 0;
    score_(in, count, cost);
    if (count > best_count || (count == best_count && cost < best_cost)) {
      best_count = count;
      best_cost = cost;
      best = T;
      if (config_.adaptive_stop) needed = adaptive_hypotheses(count, n, config_.max_iterations);
    }
  }
  return hypotheses;
}

void RigidRansac::refine(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                         const Eigen::Isometry3d& initial, RansacResult& result,
                         const PointPairCovariances* covariances) {
  result.T_prev_curr = initial;
  result.hypotheses = 0;
  double threshold = config_.inlier_threshold_m;
  std::vector<int>& inliers = result.inliers;
  inliers.clear();
  for (int round = 0; round < kMaxRefinements; ++round) {
    select_inliers(prev, curr, result.T_prev_curr, threshold, scratch_inliers_);
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
    const Eigen::Isometry3d refined = fit_anisotropic(prev, curr, inliers, covariances, result.T_prev_curr);
    // The refinement corrects the least-squares fit by noise-level amounts. A jump of more
    // than the inlier threshold means a near-degenerate geometry: keep the plain fit.
    const Eigen::Isometry3d change = result.T_prev_curr.inverse() * refined;
    if (refined.matrix().allFinite() && change.translation().norm() < config_.inlier_threshold_m &&
        Eigen::AngleAxisd(change.linear()).angle() < kMaxRefinementRotation_rad)
      result.T_prev_curr = refined;
  }
  result.status = static_cast<int>(inliers.size()) >= config_.min_inliers ? Status::Ok : Status::RansacFailed;
}

}  // namespace rgbdo
