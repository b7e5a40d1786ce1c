#include "rgbd_odometry/io/evaluate.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace rgbdo {
namespace {
constexpr double kRadToDeg = 180.0 / M_PI;
constexpr double kChi2_6_95 = 12.5916;
constexpr std::int64_t kDriftWindowNs = 1'000'000'000;
}  // namespace

ErrorStats error_stats(std::vector<double> v) {
  ErrorStats s;
  s.count = static_cast<int>(v.size());
  if (v.empty()) return s;
  double sq = 0;
  for (double x : v) sq += x * x;
  s.rmse = std::sqrt(sq / static_cast<double>(v.size()));
  std::sort(v.begin(), v.end());
  const size_t m = v.size() / 2;
  s.median = v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
  s.max = v.back();
  return s;
}

AccuracyEvaluator::AccuracyEvaluator(const GroundTruth& groundtruth, double covariance_scale_used)
    : groundtruth_(groundtruth), scale_used_(covariance_scale_used) {}

void AccuracyEvaluator::add(const PairResult& r, const Eigen::Isometry3d& pose) {
  ++pairs_;
  // The first pair also anchors its previous frame; only relative poses are ever compared.
  if (trajectory_.empty()) trajectory_.emplace_back(r.t_prev_ns, pose * r.T_prev_curr.inverse());
  trajectory_.emplace_back(r.t_curr_ns, pose);
  if (r.status != Status::Ok) {
    ++failures_[std::string(status_word(r.status))];
    return;
  }
  const auto gt_prev = groundtruth_.at(r.t_prev_ns);
  const auto gt_curr = groundtruth_.at(r.t_curr_ns);
  if (!gt_prev || !gt_curr) return;
  const Eigen::Isometry3d gt_rel = gt_prev->inverse() * *gt_curr;
  const Eigen::Isometry3d error = gt_rel.inverse() * r.T_prev_curr;
  rpe_t_.push_back(error.translation().norm());
  rpe_r_.push_back(rotation_angle(error.linear()) * kRadToDeg);
  const Vector6d e = xi_from_transform(r.T_prev_curr) - xi_from_transform(gt_rel);
  nees_.push_back(e.dot(r.covariance.ldlt().solve(e)));
  axis_nees_sum_ += e.cwiseAbs2().cwiseQuotient(r.covariance.diagonal());
}

AccuracySummary AccuracyEvaluator::summary() const {
  AccuracySummary s;
  s.pairs = pairs_;
  s.failures = failures_;
  for (const auto& [word, n] : failures_) s.failed += n;
  s.evaluated = static_cast<int>(rpe_t_.size());
  s.rpe_translation_m = error_stats(rpe_t_);
  s.rpe_rotation_deg = error_stats(rpe_r_);
  if (!nees_.empty()) {
    s.mean_nees = std::accumulate(nees_.begin(), nees_.end(), 0.0) / static_cast<double>(nees_.size());
    s.median_nees = error_stats(nees_).median;
    s.nees_within_95 = static_cast<double>(std::count_if(nees_.begin(), nees_.end(), [](double x) { return x < kChi2_6_95; })) /
                       static_cast<double>(nees_.size());
    s.axis_nees = axis_nees_sum_ / static_cast<double>(nees_.size());
    s.mean_axis_nees = s.axis_nees.mean();
    s.consistent_scale = scale_used_ * s.mean_axis_nees;
  }
  // Drift: relative pose error of the integrated trajectory over 1-second windows.
  std::vector<double> drift_t, drift_r;
  size_t j = 0;
  for (size_t i = 0; i < trajectory_.size(); ++i) {
    j = std::max(j, i + 1);
    while (j < trajectory_.size() && trajectory_[j].first - trajectory_[i].first < kDriftWindowNs) ++j;
    if (j >= trajectory_.size()) break;
    const auto gi = groundtruth_.at(trajectory_[i].first), gj = groundtruth_.at(trajectory_[j].first);
    if (!gi || !gj) continue;
    const double dt = static_cast<double>(trajectory_[j].first - trajectory_[i].first) * 1e-9;
    const Eigen::Isometry3d est = trajectory_[i].second.inverse() * trajectory_[j].second;
    const Eigen::Isometry3d error = (gi->inverse() * *gj).inverse() * est;
    drift_t.push_back(error.translation().norm() / dt);
    drift_r.push_back(rotation_angle(error.linear()) * kRadToDeg / dt);
  }
  s.drift_translation_mps = error_stats(drift_t);
  s.drift_rotation_degps = error_stats(drift_r);
  return s;
}

}  // namespace rgbdo
