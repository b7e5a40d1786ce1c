#include "rgbd_odometry/pipeline/capture_latency.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "rgbd_odometry/core/camera_mount.hpp"
#include "rgbd_odometry/core/clock.hpp"
#include "rgbd_odometry/core/geometry.hpp"
#include "rgbd_odometry/core/umeyama.hpp"

namespace rgbdo {
namespace {

constexpr std::int64_t kStepNs = 1'000'000;  // the offsets' grid
// Gyro samples held: 160 s at 50 Hz, 40 s at 200 Hz; more than the span the waiting pairs
// and the mount's pairs need.
constexpr std::size_t kGyroSamples = 8192;
constexpr std::size_t kWaitingPairs = 512;  // ~17 s at 30 Hz of pairs waiting for a late gyro
constexpr std::size_t kMountPairs = 600;    // the mount is fitted over the last pairs that turned
// Two gyro samples further apart than this are a gap: no integral across it.
constexpr std::int64_t kMaxGyroGapNs = 100'000'000;
// The bias is solved per offset with this prior, rad/s: far wider than any MEMS gyro's, it only
// keeps the solve defined before the pairs span enough time.
constexpr double kBiasPriorSigma = 0.2;
// The curvature of the cost is read this many grid steps either side of its minimum: wide
// enough that the noise of the sums does not dominate it, narrow enough to stay in the valley.
constexpr int kCurvatureSteps = 3;
// A pair whose residual at the known latency lies beyond the 99.9 % point of its predictive
// distribution is a failed fit's: 3 F(3, dof), the scatter being estimated from dof degrees of
// freedom (chi-square(3)'s 16.27 once they are many). Tabled against dof, interpolated in 1/dof.
struct GateQuantile {
  double dof, quantile;
};
constexpr std::array<GateQuantile, 12> kGate999{{{3, 423.3},
                                                 {4, 168.5},
                                                 {5, 99.6},
                                                 {7, 56.3},
                                                 {10, 37.7},
                                                 {15, 28.0},
                                                 {20, 24.3},
                                                 {30, 21.2},
                                                 {50, 19.0},
                                                 {100, 17.6},
                                                 {200, 16.9},
                                                 {1e12, 16.27}}};
// The fewest judged pairs whose median bounds the scatter.
constexpr std::size_t kLeastJudged = 7;
// A pair turned the camera when its rotation is this many sigma from none.
constexpr double kTurningChi2 = 9.0;
// A pair's rotation noise before the residuals show it, rad^2 per axis (0.1 degree), and the
// least the outlier gate allows (0.001 degree: a gyro and a camera that agree exactly).
constexpr double kInitialNoise = 3e-6;
constexpr double kLeastNoise = 3e-10;
constexpr double kRadToDeg = 180.0 / M_PI;
constexpr int kMountEveryPairs = 10;  // the mount fitted again (its cost spread: ~600 integrals)
// The share of its distance to the estimate the applied latency moves each frame.
constexpr double kApproachShare = 0.1;

}  // namespace

CaptureLatencyEstimator::CaptureLatencyEstimator(const LatencyConfig& config, const Eigen::Matrix3d& R_body_camera)
    : config_(config),
      R_body_camera_(R_body_camera),
      offsets_(1 + static_cast<int>((seconds_to_ns(config.max_s) - seconds_to_ns(config.min_s)) / kStepNs)),
      sum_tr_(static_cast<std::size_t>(offsets_), Eigen::Vector3d::Zero()),
      sum_rr_(static_cast<std::size_t>(offsets_), Eigen::Vector3d::Zero()),
      gyro_(kGyroSamples),
      waiting_(kWaitingPairs),
      recent_(kMountPairs),
      residual_(static_cast<std::size_t>(offsets_)) {
  mount_camera_.reserve(kMountPairs);
  mount_body_.reserve(kMountPairs);
}

void CaptureLatencyEstimator::add_gyro(std::span<const GyroSample> samples) {
  for (const GyroSample& s : samples) {
    if (!s.rate.allFinite()) continue;
    Gyro g{s.t_ns, s.rate, Eigen::Vector3d::Zero(), 0};
    if (gyro_count_ > 0) {
      const Gyro& last = gyro(gyro_count_ - 1);
      if (s.t_ns <= last.t_ns) continue;
      // Across a gap a new segment starts (integral_over refuses to bridge it).
      const double h = static_cast<double>(s.t_ns - last.t_ns) * 1e-9;
      g.integral = last.integral;
      g.segment = last.segment;
      if (s.t_ns - last.t_ns <= kMaxGyroGapNs)
        g.integral += 0.5 * h * (last.rate + s.rate);
      else
        ++g.segment;
    }
    if (gyro_count_ == gyro_.size()) {
      gyro_first_ = (gyro_first_ + 1) % gyro_.size();
      --gyro_count_;
    }
    gyro_[(gyro_first_ + gyro_count_) % gyro_.size()] = g;
    ++gyro_count_;
  }
  // The waiting pairs the gyro now covers at every offset searched, in order.
  while (waiting_count_ > 0) {
    const Pair& p = waiting_[waiting_first_];
    if (gyro_count_ == 0 || gyro(gyro_count_ - 1).t_ns < gyro_needed_until_ns(p.t_curr_ns)) break;
    process(p);
    waiting_first_ = (waiting_first_ + 1) % waiting_.size();
    --waiting_count_;
  }
}

std::int64_t CaptureLatencyEstimator::gyro_needed_until_ns(std::int64_t t_curr_ns) const {
  return t_curr_ns - seconds_to_ns(config_.min_s);
}

void CaptureLatencyEstimator::add_pair(std::int64_t t_prev_ns, std::int64_t t_curr_ns, const Eigen::Vector3d& rotation) {
  if (t_curr_ns <= t_prev_ns || !rotation.allFinite()) return;
  Pair p{t_prev_ns, t_curr_ns, rotation};
  if (waiting_count_ == waiting_.size()) {  // no gyro for a long time: the oldest goes unmeasured
    waiting_first_ = (waiting_first_ + 1) % waiting_.size();
    --waiting_count_;
    ++estimate_.uncovered;
  }
  waiting_[(waiting_first_ + waiting_count_) % waiting_.size()] = p;
  ++waiting_count_;
  add_gyro({});  // it may be covered already (a replay's gyro is read ahead)
}

std::optional<CaptureLatencyEstimator::Integral> CaptureLatencyEstimator::integral_at(std::int64_t t_ns) const {
  if (gyro_count_ < 2 || t_ns < gyro(0).t_ns || t_ns > gyro(gyro_count_ - 1).t_ns) return std::nullopt;
  // The last sample at or before t.
  std::size_t lo = 0, hi = gyro_count_ - 1;
  while (hi - lo > 1) {
    const std::size_t mid = (lo + hi) / 2;
    (gyro(mid).t_ns <= t_ns ? lo : hi) = mid;
  }
  const Gyro& a = gyro(lo);
  const Gyro& b = gyro(hi);
  if (b.t_ns - a.t_ns > kMaxGyroGapNs) return std::nullopt;
  // The rate linear between the samples: its integral is quadratic in time.
  const double h = static_cast<double>(b.t_ns - a.t_ns) * 1e-9;
  const double u = static_cast<double>(t_ns - a.t_ns) * 1e-9;
  return Integral{a.integral + u * a.rate + (u * u / (2 * h)) * (b.rate - a.rate), a.segment};
}

std::optional<Eigen::Vector3d> CaptureLatencyEstimator::integral_over(std::int64_t from_ns, std::int64_t to_ns) const {
  const auto a = integral_at(from_ns);
  const auto b = integral_at(to_ns);
  // A gap between them restarted the running integral: the difference would not be the rate's.
  if (!a || !b || a->segment != b->segment) return std::nullopt;
  return b->value - a->value;
}

void CaptureLatencyEstimator::process(const Pair& p) {
  ++estimate_.pairs;
  const Eigen::Vector3d theta = R_body_camera_ * p.rotation;
  const double dt = static_cast<double>(p.t_curr_ns - p.t_prev_ns) * 1e-9;
  const std::int64_t min_ns = seconds_to_ns(config_.min_s);
  // The residual at each offset, at b = 0; all or none (a gap anywhere leaves the pair out).
  std::vector<Eigen::Vector3d>& residual = residual_;
  for (int k = 0; k < offsets_; ++k) {
    const std::int64_t d = min_ns + k * kStepNs;
    const auto swept = integral_over(p.t_prev_ns - d, p.t_curr_ns - d);
    if (!swept) {
      ++estimate_.uncovered;
      return;
    }
    residual[static_cast<std::size_t>(k)] = theta - *swept;
  }
  if (estimate_.known) {
    // A failed fit's rotation says nothing of the latency: judged at the current estimate
    // against the pairs' own scatter about it.
    const double at = (estimate_.latency_s - config_.min_s) / (kStepNs * 1e-9);
    const int k = std::clamp(static_cast<int>(std::lround(at)), 0, offsets_ - 1);
    const Eigen::Vector3d r = residual[static_cast<std::size_t>(k)] + estimate_.gyro_bias * dt;
    judged_r2_.push(r.squaredNorm());
    if (outside_gate(r, residual, k)) {
      ++estimate_.rejected;
      return;
    }
  }
  // Only a camera that turned says anything of the latency (and shows the mount): its rotation
  // stands clear of the pairs' scatter about the gyro. A camera at rest adds nothing (its
  // residuals at each offset would be the gyro's noise over other samples, moving J's
  // minimum at random) and fades nothing: the estimate holds while the vehicle waits.
  const double noise = estimate_.scatter > 0 ? estimate_.scatter : kInitialNoise;
  if (theta.squaredNorm() <= kTurningChi2 * 3 * noise) {
    ++estimate_.at_rest;
    return;
  }
  const double keep = std::exp(-dt / config_.memory_s);
  sum_tt_ *= keep;
  weight_sum_ *= keep;
  for (int k = 0; k < offsets_; ++k) {
    sum_tr_[static_cast<std::size_t>(k)] *= keep;
    sum_rr_[static_cast<std::size_t>(k)] *= keep;
  }
  recent_[recent_next_] = p;
  recent_next_ = (recent_next_ + 1) % recent_.size();
  recent_count_ = std::min(recent_count_ + 1, recent_.size());
  sum_tt_.array() += dt * dt;
  weight_sum_ += 1;
  for (int k = 0; k < offsets_; ++k) {
    const Eigen::Vector3d& r = residual[static_cast<std::size_t>(k)];
    sum_tr_[static_cast<std::size_t>(k)] += dt * r;
    sum_rr_[static_cast<std::size_t>(k)] += r.cwiseProduct(r);
  }
  solve();
}

bool CaptureLatencyEstimator::outside_gate(const Eigen::Vector3d& r, const std::vector<Eigen::Vector3d>& residual,
                                           int k) const {
  // Early on the latency itself is uncertain: a pair whose rate changed moves its residual by
  // the latency's error times that change (g, the residual's slope over the offsets). Its
  // variance s I + sigma^2 g g^T, inverted by Sherman-Morrison.
  const int before = std::max(k - 1, 0), after = std::min(k + 1, offsets_ - 1);
  const Eigen::Vector3d g = (residual[static_cast<std::size_t>(after)] - residual[static_cast<std::size_t>(before)]) /
                            ((after - before) * kStepNs * 1e-9);
  // The scatter is the fit's, of the pairs let in. Should the pairs become noisier than the
  // first few (a sensor's start-up, a scene that changed), the gate would turn them all away
  // and the fit never learn it: the median of the last pairs judged, all of them, bounds it
  // from below (a failed fit now and then does not move a median).
  double s = std::max(estimate_.scatter, kLeastNoise);
  if (judged_r2_.count() >= kLeastJudged) s = std::max(s, judged_r2_.median() / kChi2_3_Median);
  const double v = estimate_.sigma_s * estimate_.sigma_s;
  const double rg = r.dot(g);
  const double mahalanobis = (r.squaredNorm() - v * rg * rg / (s + v * g.squaredNorm())) / s;
  const double dof = 3 * weight_sum_ - 4;
  auto upper = std::find_if(kGate999.begin(), kGate999.end(), [&](const GateQuantile& q) { return q.dof >= dof; });
  if (upper == kGate999.begin()) return mahalanobis > upper->quantile;
  const GateQuantile& lo = *(upper - 1);
  const double share = (1 / lo.dof - 1 / dof) / (1 / lo.dof - 1 / upper->dof);
  return mahalanobis > lo.quantile + share * (upper->quantile - lo.quantile);
}

namespace {

// A cost's minimum on the grid, refined by a parabola through its neighbours kCurvatureSteps
// either side: grid index, offset from it (s), curvature (1/s^2). Nullopt at the grid's edge or
// where the cost does not bend up.
struct Minimum {
  int index = 0;
  double vertex_s = 0, cost = 0, curvature = 0;
};
template <typename Cost>
std::optional<Minimum> minimum_of(int offsets, double step_s, Cost&& cost) {
  Minimum m;
  m.cost = std::numeric_limits<double>::infinity();
  for (int k = 0; k < offsets; ++k) {
    const double c = cost(k);
    if (c < m.cost) {
      m.cost = c;
      m.index = k;
    }
  }
  if (m.index < kCurvatureSteps || m.index >= offsets - kCurvatureSteps) return std::nullopt;
  const double h = kCurvatureSteps * step_s;
  const double before = cost(m.index - kCurvatureSteps), after = cost(m.index + kCurvatureSteps);
  const double bend = before - 2 * m.cost + after;
  if (!(bend > 0)) return std::nullopt;
  m.curvature = bend / (h * h);
  m.vertex_s = std::clamp(0.5 * h * (before - after) / bend, -h, h);
  return m;
}

}  // namespace

void CaptureLatencyEstimator::solve() {
  // The bias prior in the residuals' units: a pair's noise (the scatter, once known) over the
  // prior's variance.
  const double noise = estimate_.scatter > 0 ? estimate_.scatter : kInitialNoise;
  const Eigen::Vector3d tt = sum_tt_.array() + noise / (kBiasPriorSigma * kBiasPriorSigma);
  const auto axis_cost = [&](int k, int a) {
    const double tr = sum_tr_[static_cast<std::size_t>(k)](a);
    return sum_rr_[static_cast<std::size_t>(k)](a) - tr * tr / tt(a);
  };
  const double step_s = kStepNs * 1e-9;
  const auto best = minimum_of(offsets_, step_s, [&](int k) { return axis_cost(k, 0) + axis_cost(k, 1) + axis_cost(k, 2); });
  const double dof = 3 * weight_sum_ - 4;  // three axes a pair; the latency and three biases
  estimate_.known = best.has_value() && dof >= 3;  // else at the edge of the range searched, or too few pairs yet
  if (!estimate_.known) return;
  // Every pair weighs the same: the pairs' own covariances carry the latency terms this
  // measures, whose weights would favour the pairs that say least about it (measured: 3 ms off
  // on rendered frames, against 0.5 unweighted). The noise is the residuals' own scatter.
  estimate_.scatter = std::max(0.0, best->cost) / dof;
  const double inflation = estimate_.scatter;
  estimate_.latency_s = config_.min_s + best->index * step_s + best->vertex_s;
  estimate_.sigma_s = std::sqrt(2.0 / best->curvature * inflation);
  // The bias at the minimum: r = -b dt, so b = -sum w dt r / sum w dt^2.
  estimate_.gyro_bias = -sum_tr_[static_cast<std::size_t>(best->index)].cwiseQuotient(tt);
  // Each axis's own latency: a sensor whose streams enter the axes differently (a Kinect's
  // lagging depth leaks into the tilt rotations, not into the roll about the optical axis) is
  // no one latency, and the spread of the axes' about the common one is error that applying it
  // leaves. Weighed by each axis's information, less what their own noise explains.
  double spread = 0, axis_noise = 0, information = 0;
  for (int a = 0; a < 3; ++a) {
    const auto axis = minimum_of(offsets_, step_s, [&](int k) { return axis_cost(k, a); });
    if (!axis) continue;
    const double d = config_.min_s + axis->index * step_s + axis->vertex_s - estimate_.latency_s;
    const double variance = 2.0 / axis->curvature * inflation;
    spread += axis->curvature * d * d;
    axis_noise += axis->curvature * variance;
    information += axis->curvature;
  }
  estimate_.axis_spread_s = information > 0 ? std::sqrt(std::max(0.0, spread - axis_noise) / information) : 0;
}

MountEstimate CaptureLatencyEstimator::mount() {
  MountEstimate m;
  if (!estimate_.known || recent_count_ < 10) return m;
  const std::int64_t d = seconds_to_ns(estimate_.latency_s);
  std::vector<Eigen::Vector3d>& camera = mount_camera_;
  std::vector<Eigen::Vector3d>& body = mount_body_;
  camera.clear();
  body.clear();
  for (std::size_t i = 0; i < recent_count_; ++i) {
    const Pair& p = recent_[i];
    const auto swept = integral_over(p.t_prev_ns - d, p.t_curr_ns - d);
    if (!swept) continue;
    const double dt = static_cast<double>(p.t_curr_ns - p.t_prev_ns) * 1e-9;
    camera.push_back(p.rotation / dt);  // rates: the bias is then the fit's offset
    body.push_back(*swept / dt);
  }
  if (camera.size() < 10) return m;
  // The camera must have turned about two axes at least for the fit to fix a rotation.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& c : camera) mean += c;
  mean /= static_cast<double>(camera.size());
  Eigen::Matrix3d spread = Eigen::Matrix3d::Zero();
  for (const auto& c : camera) spread += (c - mean) * (c - mean).transpose();
  spread /= static_cast<double>(camera.size());
  const Eigen::Vector3d eig = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(spread).eigenvalues();
  constexpr double kMinRateSpread = 0.03;  // rad/s, standard deviation about the second axis
  if (!(eig(1) > kMinRateSpread * kMinRateSpread)) return m;
  Eigen::Isometry3d T;
  if (!fit_rigid(camera, body, {}, T)) return m;
  // body.*'s mount M: R_body_camera = M * forward_looking_rotation; Z-Y-X angles of M.
  const Eigen::Vector3d angles =
      euler_zyx(T.linear() * CameraExtrinsic::forward_looking_rotation().transpose()) * kRadToDeg;
  m.roll_deg = angles(0);
  m.pitch_deg = angles(1);
  m.yaw_deg = angles(2);
  m.pairs = static_cast<int>(camera.size());
  m.known = true;
  return m;
}

CaptureClock::CaptureClock(const PipelineConfig& config, GyroFeed* feed)
    : config_(config.latency),
      feed_(config.latency.enabled ? feed : nullptr),
      estimator_(config.latency, extrinsic_from(config.body).R_body_camera),
      depth_estimator_(config.latency, extrinsic_from(config.body).R_body_camera),
      R_body_camera_(extrinsic_from(config.body).R_body_camera),
      taken_(256) {
  timing_.gyro = feed_ != nullptr;
}

std::optional<double> CaptureClock::colour_latency_sigma_s() const {
  const LatencyEstimate& e = estimator_.estimate();
  if (!feed_ || !e.known || e.sigma_s > config_.converged_sigma_s) return std::nullopt;
  // What applying one latency leaves: its own error, the rotation axes' spread about it and
  // what is not applied yet.
  const double gap = e.latency_s - applied_s_;
  return std::sqrt(e.sigma_s * e.sigma_s + e.axis_spread_s * e.axis_spread_s + gap * gap);
}

MeasuredLatencySigmas CaptureClock::latency_sigmas() const {
  MeasuredLatencySigmas m;
  m.colour_s = colour_latency_sigma_s();
  m.depth_s = depth_latency_sigma_s();
  m.applied_s = feed_ ? applied_s_ : 0.0;
  m.gyro = feed_ != nullptr;
  // The translations come from both streams, from an instant between the colour's and the
  // depth's, not the rotations' one applied (on fr1_xyz restamped, pair NEES 6.08 -> 5.33 with
  // it; thinned to every 2nd frame 8.54 -> 7.86, still above the gate's share); the image shift
  // comes from the colour's, not moved with the stamps by applied_s
  // (src/pipeline/MEASUREMENTS.md#restamped-pairs-and-their-image-shift).
  if (const auto lag = depth_lag_s()) m.translation_s = std::abs(*lag);
  if (const auto retime = image_shift_retime_s()) {
    m.image_shift_retime_s = *retime;
    m.image_shift_retime_sigma_s = colour_image_latency_sigma_s();
  }
  return m;
}

double CaptureClock::colour_image_latency_sigma_s() const {
  // 2 L - L_d = L - lag, whose error is nearly free of L's (the errors the two fits share
  // cancel in the lag, depth_lag_fit.hpp).
  const double c = estimator_.estimate().sigma_s, l = depth_lag_sigma_s();
  return std::sqrt(c * c + l * l);
}

std::optional<double> CaptureClock::colour_image_latency_s() const {
  const auto lag = depth_lag_s();
  if (!lag || colour_image_latency_sigma_s() > config_.converged_sigma_s) return std::nullopt;
  return estimator_.estimate().latency_s - *lag;  // 2 L - L_d = L - lag
}

std::optional<double> CaptureClock::image_shift_retime_s() const {
  const auto colour = colour_image_latency_s();
  if (!config_.retime_image_shift || !colour) return std::nullopt;
  // Shrunk towards 0 by its own noise (r (1 - sigma^2 / r^2), at least 0): a sensor on its
  // stamps (ICL-NUIM's renderer) reads a few tenths of a millisecond either way, and its pairs,
  // which err by hundredths of a millimetre, are moved by that to no gain.
  const double r = applied_s_ - *colour, sigma = colour_image_latency_sigma_s();
  if (r == 0) return 0.0;
  return r * std::max(0.0, 1 - sigma * sigma / (r * r));
}

std::optional<double> CaptureClock::depth_lag_s() const {
  const LatencyEstimate& c = estimator_.estimate();
  const LatencyEstimate& d = depth_estimator_.estimate();
  if (!feed_ || !c.known || !d.known || c.sigma_s > config_.converged_sigma_s || d.sigma_s > config_.converged_sigma_s)
    return std::nullopt;
  return d.latency_s - c.latency_s;
}

double CaptureClock::depth_lag_sigma_s() const {
  // The two fits' errors are mostly the same (the gyro's noise, its samples' miss of the motion
  // between them) and cancel in the lag: its standard error is what the pairs' own differences
  // scatter by. Until enough of them are in, the two standard errors together, an upper bound.
  if (lag_.known()) return lag_.sigma_s();
  const double c = estimator_.estimate().sigma_s, d = depth_estimator_.estimate().sigma_s;
  return std::hypot(c, d);
}

std::optional<double> CaptureClock::depth_latency_sigma_s() const {
  const auto lag = depth_lag_s();
  if (!lag) return std::nullopt;
  return std::hypot(*lag, depth_lag_sigma_s());
}

void CaptureClock::learn_lag(const PairResult& r, std::int64_t stamp_prev_ns, std::int64_t stamp_curr_ns) {
  const LatencyEstimate& c = estimator_.estimate();
  if (r.status != Status::Ok || !r.depth_rotation.allFinite() || !c.known || c.sigma_s > config_.converged_sigma_s)
    return;
  // The slope by central difference over the offsets' grid step, 1 ms (the integral is
  // quadratic in time between samples 5-20 ms apart).
  constexpr std::int64_t h = 1'000'000;
  const std::int64_t d = seconds_to_ns(c.latency_s);
  const auto colour = estimator_.integral_over(stamp_prev_ns - d, stamp_curr_ns - d);
  const auto depth = estimator_.integral_over(r.t_depth_prev_ns - d, r.t_depth_curr_ns - d);
  const auto later = estimator_.integral_over(r.t_depth_prev_ns - d - h, r.t_depth_curr_ns - d - h);
  const auto earlier = estimator_.integral_over(r.t_depth_prev_ns - d + h, r.t_depth_curr_ns - d + h);
  if (!colour || !depth || !later || !earlier) return;
  const Eigen::Vector3d colour_residual = R_body_camera_ * rotation_vector(r.T_prev_curr.linear()) - *colour;
  const Eigen::Vector3d depth_residual = R_body_camera_ * r.depth_rotation - *depth;
  lag_.add(depth_residual - colour_residual, (*later - *earlier) / (2 * h * 1e-9));
}

void CaptureClock::stamp(PairResult& r) {
  if (!feed_) return;
  const std::int64_t stamp_prev = r.t_prev_ns, stamp_curr = r.t_curr_ns;
  // The gyro up to what this pair needs (a live feed hands over what has arrived).
  const std::int64_t until = estimator_.gyro_needed_until_ns(stamp_curr) + kMaxGyroGapNs;
  for (std::size_t n; (n = feed_->take(until, taken_)) > 0;) {
    estimator_.add_gyro(std::span<const GyroSample>(taken_.data(), n));
    depth_estimator_.add_gyro(std::span<const GyroSample>(taken_.data(), n));
    if (n < taken_.size()) break;
  }
  if (r.status == Status::Ok) {
    estimator_.add_pair(stamp_prev, stamp_curr, rotation_vector(r.T_prev_curr.linear()));
    if (r.depth_rotation.allFinite()) depth_estimator_.add_pair(r.t_depth_prev_ns, r.t_depth_curr_ns, r.depth_rotation);
    learn_lag(r, stamp_prev, stamp_curr);
  }
  const LatencyEstimate& e = estimator_.estimate();
  // The applied latency follows the estimate once it is known well enough and stands clear
  // of it (more than a standard error: a move within the estimate's own noise would only
  // stretch pairs): a tenth of the way each frame, at most latency.max_slew seconds per second
  // of frames. Steps shrink as it closes in, so that the pairs' intervals, which a step
  // stretches, stay within a fraction of a percent of their stamps' (on exact depth a 1.7-ms
  // step made pairs of rendered frames miss their ground truth by 3 times their error).
  const double dt = static_cast<double>(stamp_curr - stamp_prev) * 1e-9;
  const double gap = e.latency_s - applied_s_;
  if (e.known && e.sigma_s <= config_.converged_sigma_s && dt > 0 && std::abs(gap) > e.sigma_s) {
    const double most = std::min(config_.max_slew * dt, 0.25 * dt);
    applied_s_ += std::clamp(kApproachShare * gap, -most, most);
  }
  // Each frame keeps the capture time it was given as a pair's current frame, so that the
  // pairs chain (a consumer integrating them, the evaluation's windows); while the applied
  // latency moves, a pair's interval differs from its stamps' by that step.
  const std::int64_t shift = seconds_to_ns(applied_s_);
  const std::int64_t prev_shift = last_curr_stamp_ns_ == stamp_prev ? last_curr_shift_ns_ : shift;
  r.t_prev_ns = stamp_prev - prev_shift;
  r.t_curr_ns = stamp_curr - shift;
  last_curr_stamp_ns_ = stamp_curr;
  last_curr_shift_ns_ = shift;

  timing_.known = e.known;
  timing_.latency_s = e.latency_s;
  timing_.sigma_s = e.sigma_s;
  timing_.axis_spread_s = e.axis_spread_s;
  timing_.depth_known = depth_estimator_.estimate().known;
  timing_.depth_latency_s = depth_estimator_.estimate().latency_s;
  timing_.depth_sigma_s = depth_estimator_.estimate().sigma_s;
  timing_.applied_s = applied_s_;
  const auto colour = colour_image_latency_s();
  const auto retime = image_shift_retime_s();
  timing_.colour_image_known = colour.has_value();
  timing_.colour_image_latency_s = colour.value_or(0);
  timing_.colour_image_sigma_s = colour ? colour_image_latency_sigma_s() : 0.0;
  timing_.image_shift_retime_s = retime.value_or(0);
  timing_.pairs = e.pairs;
  timing_.uncovered = e.uncovered;
  timing_.rejected = e.rejected;
  timing_.at_rest = e.at_rest;
  if (++pairs_since_mount_ >= kMountEveryPairs) {
    pairs_since_mount_ = 0;
    const MountEstimate m = estimator_.mount();
    if (m.known) {
      timing_.mount_known = true;
      timing_.mount_roll_deg = m.roll_deg;
      timing_.mount_pitch_deg = m.pitch_deg;
      timing_.mount_yaw_deg = m.yaw_deg;
      timing_.mount_pairs = m.pairs;
    }
  }
  r.timing = timing_;
}

}  // namespace rgbdo
