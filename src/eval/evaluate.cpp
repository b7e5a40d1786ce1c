#include "rgbd_odometry/eval/evaluate.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "rgbd_odometry/core/time_format.hpp"

namespace rgbdo {
namespace {
constexpr double kRadToDeg = 180.0 / M_PI;
constexpr double kChi2_6_95 = 12.5916;
constexpr std::int64_t kWindowNs = 1'000'000'000;
// Capture-to-stamp latencies of USB cameras and mocap alignments are tens of ms; a lag beyond
// two frame periods would be a wrong clock, not a latency.
constexpr std::int64_t kMaxTimeOffsetNs = 60'000'000;
constexpr std::int64_t kTimeOffsetStepNs = 1'000'000;
constexpr int kMinTimeOffsetPairs = 30;
constexpr size_t kMaxTimeOffsetPairs = 3000;  // a long replay is subsampled: the fit needs no more

double nees_of(const Vector6d& e, const Matrix6d& c) { return e.dot(c.ldlt().solve(e)); }
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

NeesStats nees_stats(std::vector<double> v) {
  NeesStats s;
  s.count = static_cast<int>(v.size());
  if (v.empty()) return s;
  s.mean = std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
  s.median = error_stats(v).median;
  s.within_95 = static_cast<double>(std::count_if(v.begin(), v.end(), [](double x) { return x < kChi2_6_95; })) /
                static_cast<double>(v.size());
  return s;
}

AccuracyEvaluator::AccuracyEvaluator(const GroundTruth& groundtruth, GroundTruthAllowance allowance)
    : groundtruth_(groundtruth), allowance_(std::move(allowance)) {}

Matrix6d AccuracyEvaluator::allowance_covariance() const {
  Vector6d d;
  const double t2 = allowance_.translation_m * allowance_.translation_m;
  const double r2 = allowance_.rotation_rad * allowance_.rotation_rad;
  d << t2, t2, t2, r2, r2, r2;
  return d.asDiagonal();
}

void AccuracyEvaluator::add(const PairResult& r, const Eigen::Isometry3d& pose) {
  ++pairs_;
  if (groundtruth_.empty()) {
    // A live run: nothing to compare with, so nothing kept per pair (a flight's memory must
    // not grow with its length; the soak test found ~600 bytes a pair kept here).
    if (r.status != Status::Ok) ++failures_[std::string(status_word(r.status))];
    return;
  }
  // The first pair also anchors its previous frame; only relative poses are ever compared.
  if (trajectory_.empty()) {
    trajectory_.emplace_back(r.t_prev_ns, pose * r.T_prev_curr.inverse());
    groundtruth_origin_ = groundtruth_.at(r.t_prev_ns);
  }
  trajectory_.emplace_back(r.t_curr_ns, pose);
  steps_.push_back({r.t_prev_ns, r.t_curr_ns, r.status == Status::Ok, r.T_prev_curr, r.covariance});
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
  EvaluatedPair p;
  p.t_ns = r.t_curr_ns;
  p.error = xi_from_transform(r.T_prev_curr) - xi_from_transform(gt_rel);
  p.sigma = r.covariance.diagonal().cwiseSqrt();
  p.nees = nees_of(p.error, r.covariance + allowance_covariance());
  p.position = (trajectory_.front().second.inverse() * pose).translation();
  if (groundtruth_origin_) p.groundtruth_position = (groundtruth_origin_->inverse() * *gt_curr).translation();
  evaluated_.push_back(p);
  evaluated_step_.push_back(steps_.size() - 1);
}

std::vector<AccuracyEvaluator::Window> AccuracyEvaluator::windows() const {
  std::vector<Window> out;
  const Matrix6d allowance = allowance_covariance();
  for (size_t first = 0; first < steps_.size(); ++first) {
    // The shortest run of consecutive good pairs from `first` that spans at least 1 s.
    size_t last = first;
    bool usable = true;
    while (true) {
      const Step& s = steps_[last];
      usable = usable && s.ok && (last == first || steps_[last - 1].t_curr_ns == s.t_prev_ns);
      if (!usable || s.t_curr_ns - steps_[first].t_prev_ns >= kWindowNs || last + 1 == steps_.size()) break;
      ++last;
    }
    if (!usable || steps_[last].t_curr_ns - steps_[first].t_prev_ns < kWindowNs) continue;
    const auto g0 = groundtruth_.at(steps_[first].t_prev_ns), g1 = groundtruth_.at(steps_[last].t_curr_ns);
    if (!g0 || !g1) continue;
    // T = T_first ... T_last; each pair's right perturbation reaches the product through
    // Ad(B^-1), B the motions after it.
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    for (size_t k = first; k <= last; ++k) T = T * steps_[k].T;
    Matrix6d c = Matrix6d::Zero();
    Eigen::Isometry3d after = Eigen::Isometry3d::Identity();
    for (size_t k = last + 1; k-- > first;) {
      const Matrix6d ad = se3_adjoint(after.inverse());
      c += ad * right_perturbation_covariance(steps_[k].T, steps_[k].covariance) * ad.transpose();
      after = steps_[k].T * after;
    }
    const Vector6d e = right_perturbation_between(g0->inverse() * *g1, T);
    const Matrix6d c_allowed = c + allowance;
    out.push_back({first, last, nees_of(e, c_allowed), e.cwiseAbs2().cwiseQuotient(c_allowed.diagonal())});
  }
  return out;
}

AccuracySummary AccuracyEvaluator::summary() const {
  AccuracySummary s;
  s.pairs = pairs_;
  s.failures = failures_;
  for (const auto& [word, n] : failures_) s.failed += n;
  s.evaluated = static_cast<int>(rpe_t_.size());
  s.rpe_translation_m = error_stats(rpe_t_);
  s.rpe_rotation_deg = error_stats(rpe_r_);
  s.allowance = allowance_;
  const Matrix6d allowance = allowance_covariance();
  std::vector<double> nees;
  for (size_t i = 0; i < evaluated_.size(); ++i) {
    const EvaluatedPair& p = evaluated_[i];
    nees.push_back(p.nees);
    const Vector6d var = steps_[evaluated_step_[i]].covariance.diagonal() + allowance.diagonal();
    const Vector6d ratio = p.error.cwiseAbs2().cwiseQuotient(var);
    s.axis_nees += ratio;
    for (int a = 0; a < 6; ++a) s.axis_within_3sigma(a) += ratio(a) <= 9.0 ? 1 : 0;
  }
  s.pair_nees = nees_stats(nees);
  if (!evaluated_.empty()) {
    s.axis_nees /= static_cast<double>(evaluated_.size());
    s.axis_within_3sigma /= static_cast<double>(evaluated_.size());
  }
  std::vector<double> windows;
  for (const Window& w : this->windows()) {
    windows.push_back(w.nees);
    s.window_axis_nees += w.axis_ratio;
  }
  s.window_nees = nees_stats(windows);
  if (!windows.empty()) s.window_axis_nees /= static_cast<double>(windows.size());
  const std::vector<const Step*> offset_pairs = time_offset_pairs();
  s.rotation_time_offset = fit_time_offset(offset_pairs, OffsetFitPart::Rotation);
  s.depth_time_offset = fit_time_offset(offset_pairs, OffsetFitPart::OpticalAxisTranslation);

  // Lag-1 correlation (Pearson) over pairs whose successor is the next evaluated pair.
  std::vector<std::pair<Vector6d, Vector6d>> lagged;
  for (size_t i = 0; i + 1 < evaluated_.size(); ++i)
    if (evaluated_step_[i + 1] == evaluated_step_[i] + 1 &&
        steps_[evaluated_step_[i]].t_curr_ns == steps_[evaluated_step_[i + 1]].t_prev_ns)
      lagged.emplace_back(evaluated_[i].error, evaluated_[i + 1].error);
  s.lag1_pairs = static_cast<int>(lagged.size());
  if (lagged.size() >= 3) {
    Vector6d ma = Vector6d::Zero(), mb = Vector6d::Zero();
    for (const auto& [a, b] : lagged) ma += a, mb += b;
    ma /= static_cast<double>(lagged.size());
    mb /= static_cast<double>(lagged.size());
    Vector6d sab = Vector6d::Zero(), saa = Vector6d::Zero(), sbb = Vector6d::Zero();
    for (const auto& [a, b] : lagged) {
      sab += (a - ma).cwiseProduct(b - mb);
      saa += (a - ma).cwiseAbs2();
      sbb += (b - mb).cwiseAbs2();
    }
    s.lag1_correlation = sab.cwiseQuotient(saa.cwiseProduct(sbb).cwiseSqrt());
  }

  // Drift: relative pose error of the integrated trajectory over 1-second windows.
  std::vector<double> drift_t, drift_r;
  size_t j = 0;
  for (size_t i = 0; i < trajectory_.size(); ++i) {
    j = std::max(j, i + 1);
    while (j < trajectory_.size() && trajectory_[j].first - trajectory_[i].first < kWindowNs) ++j;
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

std::vector<const AccuracyEvaluator::Step*> AccuracyEvaluator::time_offset_pairs() const {
  std::vector<const Step*> usable;
  for (const Step& s : steps_)
    if (s.ok && groundtruth_.at(s.t_prev_ns - kMaxTimeOffsetNs) && groundtruth_.at(s.t_prev_ns + kMaxTimeOffsetNs) &&
        groundtruth_.at(s.t_curr_ns - kMaxTimeOffsetNs) && groundtruth_.at(s.t_curr_ns + kMaxTimeOffsetNs))
      usable.push_back(&s);
  if (usable.size() < static_cast<size_t>(kMinTimeOffsetPairs)) return {};
  const size_t stride = (usable.size() + kMaxTimeOffsetPairs - 1) / kMaxTimeOffsetPairs;
  std::vector<const Step*> pairs;
  for (size_t i = 0; i < usable.size(); i += stride) pairs.push_back(usable[i]);
  return pairs;
}

TimeOffsetFit AccuracyEvaluator::fit_time_offset(const std::vector<const Step*>& pairs, OffsetFitPart part) const {
  TimeOffsetFit fit;
  fit.max_offset_s = static_cast<double>(kMaxTimeOffsetNs) * 1e-9;
  if (pairs.empty()) return fit;
  fit.pairs = static_cast<int>(pairs.size());
  // Mean squared error of the part with the frames taken `offset` before their stamps.
  const auto mean_square = [&](std::int64_t offset_ns) {
    double sum = 0;
    for (const Step* s : pairs) {
      const auto g0 = groundtruth_.at(s->t_prev_ns - offset_ns), g1 = groundtruth_.at(s->t_curr_ns - offset_ns);
      // Cannot happen for a pair whose search ends were found (a gap the lookup refuses is
      // longer than the search), but a shift not judged on every pair must never win.
      if (!g0 || !g1) return std::numeric_limits<double>::infinity();
      const Eigen::Isometry3d gt_rel = g0->inverse() * *g1;
      const double e = part == OffsetFitPart::Rotation ? rotation_angle(gt_rel.linear().transpose() * s->T.linear())
                                                       : s->T.translation().z() - gt_rel.translation().z();
      sum += e * e;
    }
    return sum / static_cast<double>(pairs.size());
  };
  const int steps = static_cast<int>(kMaxTimeOffsetNs / kTimeOffsetStepNs);
  std::vector<double> cost;
  for (int k = -steps; k <= steps; ++k) cost.push_back(mean_square(k * kTimeOffsetStepNs));
  const auto best = static_cast<int>(std::min_element(cost.begin(), cost.end()) - cost.begin());
  fit.rmse_at_stamps = std::sqrt(cost[static_cast<size_t>(steps)]);
  // At the edge, or no finite cost: no minimum inside the search.
  if (best == 0 || best == 2 * steps || !std::isfinite(cost[static_cast<size_t>(best)])) return fit;
  // The parabola through the best step and its neighbours.
  const double a = cost[static_cast<size_t>(best - 1)], b = cost[static_cast<size_t>(best)],
               c = cost[static_cast<size_t>(best + 1)];
  const double curvature = std::isfinite(a) && std::isfinite(c) ? a - 2 * b + c : 0.0;
  const double vertex = curvature > 0 ? std::clamp(0.5 * (a - c) / curvature, -0.5, 0.5) : 0.0;
  const double offset_ns = (best - steps + vertex) * static_cast<double>(kTimeOffsetStepNs);
  fit.found = true;
  fit.offset_s = offset_ns * 1e-9;
  fit.rmse_at_offset = std::sqrt(mean_square(std::llround(offset_ns)));
  // Least squares in one parameter: var = s^2 / sum |g|^2, g the part's rate of change with
  // the offset, where cost'' = 2 sum |g|^2 / n and each of the part's components (3 of a
  // rotation's angle, 1 of tz) has the variance s^2 = cost / components at the minimum.
  if (curvature > 0) {
    const double step_s = static_cast<double>(kTimeOffsetStepNs) * 1e-9;
    const double components = part == OffsetFitPart::Rotation ? 3.0 : 1.0;
    fit.standard_error_s =
        std::sqrt(2 * b * step_s * step_s / (components * static_cast<double>(pairs.size()) * curvature));
  }
  return fit;
}

std::vector<EvaluatedPair> AccuracyEvaluator::evaluated_pairs() const {
  std::vector<EvaluatedPair> rows = evaluated_;
  std::map<size_t, double> ending_at;  // the shortest window ending at each pair
  for (const Window& w : windows()) ending_at[w.last] = w.nees;
  for (size_t i = 0; i < rows.size(); ++i)
    if (const auto w = ending_at.find(evaluated_step_[i]); w != ending_at.end()) rows[i].window_nees = w->second;
  return rows;
}

void AccuracyEvaluator::write_csv(const std::string& path) const {
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot create the evaluation file '" + path + "'");
  f << "# rgbd-odometry evaluation against ground truth; error = xi(estimate) - xi(ground truth), xi = (t [m], "
       "rotation vector [rad]); sd = sqrt of the reported variance (no allowance)\n";
  f << "# ground-truth allowance: " << allowance_.translation_m << " m, " << allowance_.rotation_rad << " rad ("
    << allowance_.origin << ")\n";
  f << "t_s,e_tx,e_ty,e_tz,e_rx,e_ry,e_rz,sd_tx,sd_ty,sd_tz,sd_rx,sd_ry,sd_rz,nees,window_nees,x,y,z,gt_x,gt_y,gt_z\n";
  f << std::setprecision(10);
  for (const EvaluatedPair& p : evaluated_pairs()) {
    f << format_seconds(p.t_ns);
    for (int a = 0; a < 6; ++a) f << ',' << p.error(a);
    for (int a = 0; a < 6; ++a) f << ',' << p.sigma(a);
    f << ',' << p.nees << ',';
    if (p.window_nees >= 0) f << p.window_nees;
    for (int a = 0; a < 3; ++a) f << ',' << p.position(a);
    for (int a = 0; a < 3; ++a) f << ',' << p.groundtruth_position(a);
    f << '\n';
  }
  if (!f.flush()) throw std::runtime_error("cannot write the evaluation file '" + path + "'");
}

}  // namespace rgbdo
