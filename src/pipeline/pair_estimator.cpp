#include "rgbd_odometry/pipeline/pair_estimator.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>

#include "rgbd_odometry/core/clock.hpp"
#include "rgbd_odometry/core/cost_stage.hpp"
#include "rgbd_odometry/pipeline/noise_model.hpp"
#include "rgbd_odometry/core/splitmix64.hpp"

namespace rgbdo {
namespace {

using Clock = std::chrono::steady_clock;

// A pair whose motion its own covariance cannot tell from none (xi^T C^-1 xi under chi^2(6)'s
// 99 % point) teaches the learnt sensor constants nothing: see PairEstimator::estimate.
constexpr double kChi2_6_99 = 16.81;

// The points' mean 1/Z: the depth of the image shift both the depth clock and the latency
// terms keep (0 without points).
double mean_inverse_depth(const std::vector<Eigen::Vector3d>& points) {
  double sum = 0;
  for (const Eigen::Vector3d& p : points) sum += 1.0 / p.z();
  return points.empty() ? 0.0 : sum / static_cast<double>(points.size());
}

MotionPrior motion_of(const PairRate& pair) {
  MotionPrior m;
  m.velocity_mps = pair.rate.head<3>();
  m.angular_velocity_radps = pair.rate.tail<3>();
  return m;
}

// Decorrelates the per-pair random streams while keeping every pair replayable from the seed:
// the (index + 1)-th output of a splitmix64 generator started at the seed.
std::uint64_t mix(std::uint64_t seed, std::uint64_t index) {
  return splitmix64_mix(seed + kSplitMix64Increment * (index + 1));
}

// A pair's random streams follow from what its two frames hold, not from where the pair falls
// in a run: the same two frames give the same result whenever they come (a replay, a live run
// that skipped other frames, the thousandth pass of a looped recording). Eight descriptor rows
// of each frame, evenly spread, and the keypoint counts are plenty to tell frames apart.
std::uint64_t content_key(const ProcessedFrame& prev, const ProcessedFrame& curr) {
  std::uint64_t key = 0;
  const auto absorb = [&key](std::uint64_t word) { key = splitmix64_mix(key ^ (word + kSplitMix64Increment)); };
  for (const ProcessedFrame* f : {&prev, &curr}) {
    const cv::Mat& d = f->features.descriptors;
    absorb(static_cast<std::uint64_t>(f->features.keypoints.size()));
    if (d.empty()) continue;
    const size_t row_bytes = static_cast<size_t>(d.cols) * d.elemSize();
    for (int k = 0; k < 8; ++k) {
      const std::uint8_t* row = d.ptr<std::uint8_t>(static_cast<int>(static_cast<std::int64_t>(d.rows - 1) * k / 7));
      for (size_t b = 0; b + 8 <= row_bytes; b += 8) {
        std::uint64_t word = 0;
        std::memcpy(&word, row + b, 8);
        absorb(word);
      }
    }
  }
  return key;
}

// Where each keypoint of the previous frame appears in the current one (normalised image
// coordinates) if the camera moved by the prior's velocity over dt_s; NaN without depth.
// First order in the rotation (a few degrees per frame at most: the window absorbs the
// rest) and plain IEEE operations, so every build predicts the same positions.
void predict_positions(const KeypointGeometry& prev, const MotionPrior& prior, double dt_s,
                       std::vector<Eigen::Vector2d>& out) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double tx = prior.velocity_mps.x() * dt_s, ty = prior.velocity_mps.y() * dt_s, tz = prior.velocity_mps.z() * dt_s;
  const double ax = prior.angular_velocity_radps.x() * dt_s, ay = prior.angular_velocity_radps.y() * dt_s,
               az = prior.angular_velocity_radps.z() * dt_s;
  out.resize(prev.depth_m.size());
  for (size_t i = 0; i < out.size(); ++i) {
    const double z = prev.depth_m[i];
    if (!(z > 0)) {
      out[i] = {nan, nan};
      continue;
    }
    // P_curr = R^T (P_prev - t) with R = exp([a]x) ~ I + [a]x: P_curr ~ d - a x d, d = P_prev - t.
    const double dx = prev.normalized[i].x() * z - tx, dy = prev.normalized[i].y() * z - ty, dz = z - tz;
    const double px = dx - (ay * dz - az * dy), py = dy - (az * dx - ax * dz), pz = dz - (ax * dy - ay * dx);
    out[i] = pz > 0 ? Eigen::Vector2d(px / pz, py / pz) : Eigen::Vector2d(nan, nan);
  }
}

}  // namespace

PairEstimator::PairEstimator(const PipelineConfig& config)
    : config_(config),
      paper_noise_(config.covariance.model == "paper"),
      noise_(sensor_noise(config)),
      fit_noise_(fit_weight_noise(noise_)),
      tracking_(tracks_keypoints(config)),
      matcher_(config.matching.ratio),
      tracker_(config.camera, config.features.orb_scale_factor, config.features.max_features),
      ransac_(config.ransac, sensor_noise(config), config.features.max_features),
      covariance_(config.covariance, config.features.max_features),
      aligner_(config.camera, config.refinement, config.covariance.depth_noise_coeff, config.depth.units_per_m),
      alignment_trust_(config.refinement),
      depth_lag_(config.refinement),
      depth_clock_(config.depth.lag_beyond_stamps_s, config.depth.tilt_lag_beyond_stamps_s),
      depth_noise_(config.covariance.depth_noise_coeff),
      keypoint_sigma_(config.covariance.pixel_sigma_px, config.features.orb_scale_factor, config.features.orb_levels,
                      config.features.max_features),
      latency_(latency_sigmas(config.covariance)) {
  // Sized once for the largest possible frame: the pair stage never allocates afterwards.
  const auto capacity = static_cast<size_t>(config.features.max_features);
  matches_.reserve(capacity);
  matcher_.reserve(config.features.max_features);
  predicted_.reserve(capacity);
  for (auto* v : {&pairs_.prev, &pairs_.curr, &inlier_prev_, &inlier_curr_}) v->reserve(capacity);
  inlier_prev_noise_.reserve(capacity);
  inlier_cells_.reserve(capacity);
  inlier_curr_noise_.reserve(capacity);
  pairs_.match_index.reserve(capacity);
  pair_covariances_.prev.reserve(capacity);
  pair_covariances_.curr.reserve(capacity);
  fit_.inliers.reserve(capacity);
  refined_.inliers.reserve(capacity);
}

Status PairEstimator::match_and_fit(const ProcessedFrame& prev, const ProcessedFrame& curr, const MotionPrior* window_prior,
                                   double dt_s, const MotionPrior* timing_prior, std::uint64_t pair_key, PairResult& r) {
  mark_cost_stage(CostStage::Match);
  auto t0 = Clock::now();
  if (window_prior != nullptr) {
    predict_positions(prev.geometry, *window_prior, dt_s, predicted_);
    matcher_.match_within(prev.features.descriptors, curr.features.descriptors, predicted_, curr.geometry.normalized,
                          config_.matching.window_px / config_.camera.fx, matches_);
  } else {
    matcher_.match(prev.features.descriptors, curr.features.descriptors, matches_);
  }
  r.matches = static_cast<int>(matches_.size());
  r.times.match_ms += ms_since(t0);
  if (r.matches < config_.ransac.min_inliers) return Status::TooFewMatches;

  mark_cost_stage(CostStage::PointPairs);
  t0 = Clock::now();
  build_point_pairs(matches_, prev.geometry, prev.times, curr.geometry, curr.times, timing_prior, pairs_);
  r.point_pairs = static_cast<int>(pairs_.size());
  r.times.backproject_ms += ms_since(t0);
  if (r.point_pairs < config_.ransac.min_inliers) return Status::TooFewMatches;

  // Its own stream per pair (the covariance's is another), the same for a second attempt.
  Rng ransac_rng(mix(config_.seed, 2 * pair_key));
  mark_cost_stage(CostStage::Ransac);
  t0 = Clock::now();
  describe_pair_noise(prev, curr);
  ransac_.estimate(pairs_.prev, pairs_.curr, ransac_rng, fit_, &pair_covariances_);
  r.times.ransac_ms += ms_since(t0);
  return fit_.status;
}

// Detectors other than ORB's pyramid number their octaves otherwise: kept within ORB's levels.
int PairEstimator::keypoint_level(const ProcessedFrame& frame, size_t keypoint) const {
  return std::clamp(frame.features.keypoints[keypoint].octave, 0, config_.features.orb_levels - 1);
}

PointNoise PairEstimator::keypoint_noise(const ProcessedFrame& frame, size_t keypoint, const Eigen::Vector3d& p) const {
  return physical_point_noise(p, keypoint_level(frame, keypoint), frame.geometry.depth_gradient[keypoint], noise_);
}

Eigen::Matrix3d PairEstimator::fit_covariance(const ProcessedFrame& frame, size_t keypoint,
                                              const Eigen::Vector3d& p) const {
  const double sigma_px = fit_sigma_px_[static_cast<size_t>(keypoint_level(frame, keypoint))];
  return physical_point_noise_px(p, sigma_px, frame.geometry.depth_gradient[keypoint], fit_noise_).covariance();
}

void PairEstimator::describe_pair_noise(const ProcessedFrame& prev, const ProcessedFrame& curr) {
  pair_covariances_.prev.clear();
  pair_covariances_.curr.clear();
  if (paper_noise_) return;  // the paper's fit: point_covariance()
  // The constants as learnt so far.
  fit_noise_.depth_noise_coeff = in_weight_steps(depth_noise_.coeff());
  for (int l = 0; l < keypoint_sigma_.levels(); ++l)
    fit_sigma_px_[static_cast<size_t>(l)] = in_weight_steps(keypoint_sigma_.sigma_px(l));
  for (size_t k = 0; k < pairs_.size(); ++k) {
    const Match& m = matches_[static_cast<size_t>(pairs_.match_index[k])];
    pair_covariances_.prev.push_back(fit_covariance(prev, static_cast<size_t>(m.prev), pairs_.prev[k]));
    pair_covariances_.curr.push_back(fit_covariance(curr, static_cast<size_t>(m.curr), pairs_.curr[k]));
  }
}

int PairEstimator::track_keypoints(const ProcessedFrame& prev, const ProcessedFrame& curr) {
  if (!tracking_ || prev.gray.empty() || curr.gray.empty()) return 0;
  return tracker_.track(prev.gray, prev.geometry, curr.gray, curr.geometry, curr.features.keypoints, matches_,
                        pairs_.match_index, tracked_);
}

void PairEstimator::learn_keypoint_sigma(const ProcessedFrame& prev, const ProcessedFrame& curr,
                                         const KeypointGeometry& curr_geometry) {
  const Eigen::Isometry3d curr_from_prev = fit_.T_prev_curr.inverse();
  for (int k : fit_.inliers) {
    const Match& m = matches_[static_cast<size_t>(pairs_.match_index[static_cast<size_t>(k)])];
    const int level = prev.features.keypoints[static_cast<size_t>(m.prev)].octave;
    if (level != curr.features.keypoints[static_cast<size_t>(m.curr)].octave) continue;
    const Eigen::Vector3d q = curr_from_prev * pairs_.prev[static_cast<size_t>(k)];
    if (!(q.z() > 0)) continue;
    const Eigen::Vector2d off = q.head<2>() / q.z() - curr_geometry.normalized[static_cast<size_t>(m.curr)];
    keypoint_sigma_.add(level, std::hypot(off.x() * config_.camera.fx, off.y() * config_.camera.fy));
  }
  keypoint_sigma_.update();
}

void PairEstimator::describe_inlier_noise(const ProcessedFrame& prev, const ProcessedFrame& curr,
                                          const KeypointGeometry& curr_geometry, double dt_s) {
  inlier_prev_noise_.clear();
  inlier_curr_noise_.clear();
  inlier_cells_.clear();
  const double cell_px = config_.covariance.resample_cell_px;
  const int cell_columns = cell_px > 0 ? static_cast<int>(std::ceil(config_.camera.width / cell_px)) : 1;
  // Depth rates at the keypoints under this pair's own motion, as the timing compensation
  // (backproject.hpp) computes them: what a capture-time error does to each depth.
  const MotionPrior own = dt_s > 0 ? motion_from(fit_.T_prev_curr, dt_s) : MotionPrior{};
  const auto depth_rate = [&](const Eigen::Vector3d& p, const Eigen::Vector2d& gradient,
                              const Eigen::Vector2d& pixel_velocity) {
    return -(own.velocity_mps + own.angular_velocity_radps.cross(p)).z() - gradient.dot(pixel_velocity);
  };
  for (size_t n = 0; n < fit_.inliers.size(); ++n) {
    const auto k = static_cast<size_t>(fit_.inliers[n]);
    const Match& m = matches_[static_cast<size_t>(pairs_.match_index[k])];
    const auto i = static_cast<size_t>(m.prev), j = static_cast<size_t>(m.curr);
    const Eigen::Vector2d pixel_velocity =
        dt_s > 0 ? Eigen::Vector2d((curr_geometry.pixel[j] - prev.geometry.pixel[i]) / dt_s) : Eigen::Vector2d::Zero();
    PointNoise np = keypoint_noise(prev, i, pairs_.prev[k]);
    PointNoise nc = keypoint_noise(curr, j, pairs_.curr[k]);
    np.depth_rate_mps = depth_rate(pairs_.prev[k], prev.geometry.depth_gradient[i], pixel_velocity);
    nc.depth_rate_mps = depth_rate(pairs_.curr[k], curr_geometry.depth_gradient[j], pixel_velocity);
    inlier_prev_noise_.push_back(np);
    inlier_curr_noise_.push_back(nc);
    if (cell_px > 0) {
      const Eigen::Vector2d& u = curr_geometry.pixel[j];
      const int column = std::clamp(static_cast<int>(u.x() / cell_px), 0, cell_columns - 1);
      const int row = std::clamp(static_cast<int>(u.y() / cell_px), 0, 255);
      inlier_cells_.push_back(static_cast<std::uint16_t>(std::min(row * cell_columns + column, 65535)));
    }
  }
}

int PairEstimator::refine_with_depth(const ProcessedFrame& prev, const ProcessedFrame& curr, double dt_s,
                                     bool learn, Matrix6d& covariance, bool& depth_trusted) {
  if (prev.cloud.empty() || curr.cloud.empty() || !(dt_s > 0)) return 0;
  // The depth maps were taken at the depth instants: their alignment measures the motion over
  // the depth interval, carried to the colour interval at constant velocity. Two colour frames
  // sharing one depth frame (or nearly) leave nothing to align.
  const double dt_depth = static_cast<double>(curr.times.t_depth_ns - prev.times.t_depth_ns) * 1e-9;
  if (!(dt_depth >= 0.5 * dt_s && dt_depth <= 2 * dt_s)) return 0;
  const double to_depth = dt_depth / dt_s;
  const Eigen::Isometry3d seed = transform_from_xi(xi_from_transform(fit_.T_prev_curr) * to_depth);
  aligner_.align(prev.cloud, curr.cloud, seed, alignment_);
  if (!alignment_.ok) return 0;
  depth_rotation_ = rotation_vector(alignment_.T_prev_curr.linear());  // over the depth interval, unfused
  if (learn) depth_noise_.update(alignment_.depth_noise_coeff);
  const Eigen::Isometry3d T_depth = transform_from_xi(xi_from_transform(alignment_.T_prev_curr) / to_depth);
  const Matrix6d own_cov = alignment_.covariance / (to_depth * to_depth);
  const Matrix6d feature_cov = right_perturbation_covariance(fit_.T_prev_curr, covariance);
  const Vector6d difference = right_perturbation_between(fit_.T_prev_curr, T_depth);
  if (learn && last_feature_pair_) {
    // The depth's lag behind the colour, learnt and reported (DepthLagEstimate). Not corrected
    // here: the change of rate it would be multiplied by is the features' own, as noisy per
    // pair as the correction would be large (fr1: 0.3 deg either way), and it would make the
    // two estimates' errors correlated.
    const PairRate& last = *last_feature_pair_;
    const Vector6d delta_rate = xi_from_transform(fit_.T_prev_curr) / dt_s - last.rate;
    const double noise = (covariance.bottomRightCorner<3, 3>().trace() / (dt_s * dt_s)) +
                         last.covariance.bottomRightCorner<3, 3>().trace() / (last.dt_s * last.dt_s);
    depth_lag_.update(difference.tail<3>(), delta_rate.tail<3>(), noise);
  }
  Matrix6d depth_cov = alignment_trust_.scaled(own_cov);
  depth_cov.bottomRightCorner<3, 3>() += depth_lag_.rotation_covariance();
  // Learnt from every fully constrained pair, at rest too (estimate() says why), before the
  // agreement test, which must not censor it.
  if (alignment_.constrained == 6)
    alignment_trust_.update(difference, feature_cov, own_cov, depth_lag_.rotation_covariance());
  // A sensor whose alignment errs by several times what its residuals say has errors they
  // cannot see (a structured-light depth map's distortion, its lag): they do not average out
  // from pair to pair, and fused at the learnt factors they cost more over a second than they
  // gain per pair (TUM fr1's Kinect: factors 3-7; fused, pair error 4.69 -> 3.55 mm but 1-s
  // drift 0.022 -> 0.027 m/s). Nor can the factors be relied on while the depth is learnt to
  // lag the colour: where the features are weak their own error fills the difference, and the
  // factors fall to their floor (TUM fr1 at 200-300 features a frame: fused, pair NEES 9-16 and
  // 1-s rotation drift up by a third). Such a sensor's alignment is fused at a fixed factor
  // instead, weighed down so far that its slow errors stay below the features' over a second
  // while it still takes off each pair the errors the features cannot see (the split of an
  // image shift between sideways translation and rotation;
  // src/pipeline/MEASUREMENTS.md#on-the-kinect-at-fixed-factors-not-the-learnt-ones), or not at
  // all when that factor is 0.
  const bool trusted =
      std::max(alignment_trust_.translation_scale(), alignment_trust_.rotation_scale()) <=
          config_.refinement.max_sigma_scale_fused &&
      std::abs(depth_lag_.lag_s()) <= config_.refinement.max_depth_lag_fused_s;
  // The pair's covariance is then that of the estimate so made, with the alignment's error per
  // pair as the learnt factors have it (consistent pair by pair), not the fixed factors' size.
  const Matrix6d depth_error_cov = depth_cov;
  if (!trusted) {
    const RefinementConfig& r = config_.refinement;
    if (!(r.distrusted_sigma_scale > 0)) return 0;
    Vector6d k;
    k << r.distrusted_sigma_scale, r.distrusted_sigma_scale, r.distrusted_sigma_scale_optical_axis,
        Eigen::Vector3d::Constant(r.distrusted_sigma_scale_rotation);
    depth_cov = k.asDiagonal() * own_cov * k.asDiagonal();
  }
  Eigen::Isometry3d fused;
  Matrix6d fused_cov;
  if (!fuse_estimates(fit_.T_prev_curr, feature_cov, T_depth, depth_cov, alignment_.basis, alignment_.constrained,
                      fused, fused_cov, trusted ? nullptr : &depth_error_cov))
    return 0;
  fit_.T_prev_curr = fused;
  covariance = xi_covariance_from_right_perturbation(fused, fused_cov);
  depth_trusted = trusted;
  return alignment_.points;
}

PairResult PairEstimator::estimate(const ProcessedFrame& prev, const ProcessedFrame& curr) {
  PairResult r;
  // Stamped on the host clock at the newer frame's capture, the interval the timeline's: a
  // step of the host lead between the two frames (sensor/device_clock.hpp) moves the pair, it
  // never stretches or shrinks the interval the motion is divided by.
  r.t_curr_ns = curr.times.host_colour_ns();
  r.t_prev_ns = r.t_curr_ns - (curr.times.t_colour_ns - prev.times.t_colour_ns);
  r.features_prev = static_cast<int>(prev.features.keypoints.size());
  r.features_curr = static_cast<int>(curr.features.keypoints.size());
  if (curr.times.t_colour_ns <= prev.times.t_colour_ns) {
    // Before any other verdict: the frame is dropped whatever its content, and the
    // estimator's state (the last velocity) stays that of the previous frame's pair.
    r.status = Status::StampNotIncreasing;
    r.frame_dropped = true;
    return r;
  }
  if (curr.status == Status::NoDepth && prev.status == Status::Ok && r.t_curr_ns - r.t_prev_ns <= kMaxBridgedGapNs) {
    // A colour frame without its depth (none within 20 ms, or an empty image: the sensor's
    // hiccup) is dropped and the next frame pairs with this one's predecessor, as a live reader
    // that gives such a frame up does. Failed, it cost two pairs, the motion over both and the
    // keyframe chain (the textureless TUM fr3 head, 3 such frames: 1-s drift 0.0287 -> 0.0186 m/s
    // bridged; src/pipeline/MEASUREMENTS.md).
    r.status = Status::NoDepth;
    r.frame_dropped = true;
    return r;
  }
  const auto fail = [&](Status s) {
    r.status = s;
    last_pair_.reset();  // a gap: the old velocity says nothing about the next pair
    last_feature_pair_.reset();
    depth_clock_.forget();
    return r;
  };
  // The newer frame's problem is the news; the older one's was reported with its own pair.
  if (curr.status != Status::Ok) return fail(curr.status);
  if (prev.status != Status::Ok) return fail(prev.status);
  const double dt_s = static_cast<double>(r.t_curr_ns - r.t_prev_ns) * 1e-9;
  stamp_jitter_.add(prev.times, curr.times);
  const std::uint64_t pair_key = content_key(prev, curr);

  const CostStagesEnd stages_end;
  const bool compensate = config_.depth.compensate_timing && dt_s > 0;
  if (const Status solved = fit_features(prev, curr, dt_s, compensate, pair_key, r); solved != Status::Ok)
    return fail(solved);
  const KeypointGeometry& curr_geometry = track_and_refit(prev, curr, dt_s, compensate, r);

  mark_cost_stage(CostStage::Covariance);
  const Clock::time_point t0 = Clock::now();
  Matrix6d cov;
  if (!features_covariance(prev, curr, curr_geometry, dt_s, pair_key, cov)) {
    r.times.covariance_ms = ms_since(t0);
    return fail(Status::CovarianceFailed);
  }
  // A camera at rest, or as good as, shows neither how its keypoints are localised under
  // motion, nor the depth noise a moving scene brings, nor a lag: its pair is solved and
  // reported as any other, but the learnt constants skip it. Otherwise a drone waiting on the
  // ground would teach them that its sensor is exact (30 identical frames before fr1_xyz: the
  // moving pairs after them drifted 0.893 -> 1.031 deg/s while the constants climbed back from
  // their floors). The alignment's trust is not held: on exact depth the slow pairs are where
  // it learns (ICL's first 20 pairs; holding it cost 0.49 -> 0.56 mm a pair there).
  const Vector6d xi = xi_from_transform(fit_.T_prev_curr);
  const bool learn = !paper_noise_ && xi.dot(cov.ldlt().solve(xi)) >= kChi2_6_99;
  if (learn) learn_keypoint_sigma(prev, curr, curr_geometry);
  if (config_.refinement.enabled && !paper_noise_) fuse_depth_alignment(prev, curr, dt_s, learn, xi, cov, r);
  r.motion_covariance = cov;
  if (dt_s > 0) add_latency_terms(dt_s, cov);
  r.times.covariance_ms = ms_since(t0);

  r.status = Status::Ok;
  r.inliers = static_cast<int>(fit_.inliers.size());
  r.inlier_threshold_m = fit_.threshold_m;
  // The inliers' depth only where a tilt is carried (depth.tilt_lag_beyond_stamps_s) or the
  // image shift retimed.
  const double inverse_depth = config_.depth.tilt_lag_beyond_stamps_s != 0 || latency_.image_shift_retime_s != 0
                                   ? mean_inverse_depth(inlier_curr_)
                                   : 0.0;
  r.T_prev_curr =
      depth_clock_.carry(fit_.T_prev_curr, dt_s, applied_s_, rotations_timed_, inverse_depth, latency_.image_shift_retime_s);
  r.depth_shift = depth_clock_.frame_shift();
  r.covariance = cov;
  return r;
}

Status PairEstimator::fit_features(const ProcessedFrame& prev, const ProcessedFrame& curr, double dt_s,
                                   bool compensate, std::uint64_t pair_key, PairResult& r) {
  // Before this pair is solved, the previous pair's velocity is the best guess (zero after a gap).
  const MotionPrior prior = last_pair_ ? motion_of(*last_pair_) : MotionPrior{};
  const bool windowed = config_.matching.window_px > 0 && prev.features.descriptors.type() == CV_8UC1 &&
                        curr.features.descriptors.type() == CV_8UC1;
  Status solved = match_and_fit(prev, curr, windowed ? &prior : nullptr, dt_s, compensate ? &prior : nullptr, pair_key, r);
  if (windowed && (solved != Status::Ok || fit_.inliers.size() < 2 * static_cast<size_t>(config_.ransac.min_inliers))) {
    // The prior was wrong (a jolt, a gap) or the scene is bare: the paper's search over all pairs.
    r.rematched = true;
    solved = match_and_fit(prev, curr, nullptr, dt_s, compensate ? &prior : nullptr, pair_key, r);
  }
  return solved;
}

const KeypointGeometry& PairEstimator::track_and_refit(const ProcessedFrame& prev, const ProcessedFrame& curr,
                                                       double dt_s, bool compensate, PairResult& r) {
  mark_cost_stage(CostStage::Track);
  Clock::time_point t0 = Clock::now();
  r.tracked = track_keypoints(prev, curr);
  const bool tracked = r.tracked > 0;
  const KeypointGeometry& curr_geometry = tracked ? tracked_ : curr.geometry;
  r.times.match_ms += ms_since(t0);  // the matches made precise: the log's stage times keep their columns
  if (!compensate && !tracked) return curr_geometry;
  // Second pass, on the tracked keypoints: carry the depths to colour time with this pair's
  // own velocity, which is better than the previous pair's whenever the depth frames are far
  // enough apart.
  mark_cost_stage(CostStage::PointPairs);
  t0 = Clock::now();
  const MotionPrior own = motion_from(fit_.T_prev_curr, dt_s);
  build_point_pairs(matches_, prev.geometry, prev.times, curr_geometry, curr.times, compensate ? &own : nullptr,
                    pairs_);
  r.times.backproject_ms += ms_since(t0);
  mark_cost_stage(CostStage::Ransac);
  t0 = Clock::now();
  describe_pair_noise(prev, curr);
  ransac_.refine(pairs_.prev, pairs_.curr, fit_.T_prev_curr, refined_, &pair_covariances_);
  r.times.ransac_ms += ms_since(t0);
  if (refined_.status == Status::Ok) {
    refined_.hypotheses = fit_.hypotheses;
    std::swap(fit_, refined_);  // swaps buffers, allocates nothing
  }
  return curr_geometry;
}

bool PairEstimator::features_covariance(const ProcessedFrame& prev, const ProcessedFrame& curr,
                                        const KeypointGeometry& curr_geometry, double dt_s, std::uint64_t pair_key,
                                        Matrix6d& cov) {
  Rng covariance_rng(mix(config_.seed, 2 * pair_key + 1));
  inlier_prev_.clear();
  inlier_curr_.clear();
  for (int k : fit_.inliers) {
    inlier_prev_.push_back(pairs_.prev[static_cast<size_t>(k)]);
    inlier_curr_.push_back(pairs_.curr[static_cast<size_t>(k)]);
  }
  if (paper_noise_) return covariance_.estimate(inlier_prev_, inlier_curr_, fit_.T_prev_curr, covariance_rng, cov);
  describe_inlier_noise(prev, curr, curr_geometry, dt_s);
  const double timing_sigma_s =
      config_.covariance.timing_sigma_s >= 0 ? config_.covariance.timing_sigma_s : stamp_jitter_.offset_sigma_s();
  return covariance_.estimate(inlier_prev_, inlier_curr_, inlier_prev_noise_, inlier_curr_noise_, inlier_cells_,
                              fit_.T_prev_curr, timing_sigma_s, covariance_rng, cov);
}

void PairEstimator::fuse_depth_alignment(const ProcessedFrame& prev, const ProcessedFrame& curr, double dt_s,
                                         bool learn, const Vector6d& features_xi, Matrix6d& cov, PairResult& r) {
  mark_cost_stage(CostStage::Refine);
  // The features' own rate, kept before the fusion changes fit_ and cov (last_feature_pair_).
  const std::optional<PairRate> features_only =
      dt_s > 0 ? std::optional<PairRate>(PairRate{features_xi / dt_s, cov, dt_s}) : std::nullopt;
  depth_rotation_.reset();
  r.depth_points = refine_with_depth(prev, curr, dt_s, learn, cov, r.depth_trusted);
  if (depth_rotation_) {
    r.depth_rotation = *depth_rotation_;
    r.t_depth_prev_ns = r.t_prev_ns - (prev.times.t_colour_ns - prev.times.t_depth_ns);
    r.t_depth_curr_ns = r.t_curr_ns - (curr.times.t_colour_ns - curr.times.t_depth_ns);
  }
  if (features_only) last_feature_pair_ = features_only;
  r.sensor = {alignment_trust_.translation_scale(), alignment_trust_.rotation_scale(), depth_lag_.lag_s(),
              depth_noise_.coeff(), keypoint_sigma_.sigma_px(0),
              keypoint_sigma_.sigma_px(keypoint_sigma_.levels() - 1), keypoint_sigma_.levels() - 1};
  mark_cost_stage(CostStage::Covariance);
}

void PairEstimator::add_latency_terms(double dt_s, Matrix6d& cov) {
  // The inliers' mean inverse depth, which only a restamped pair's image-shift term uses.
  const double inverse_depth = latency_.image_shift_term() ? mean_inverse_depth(inlier_prev_) : 0.0;
  const PairRate own{xi_from_transform(fit_.T_prev_curr) / dt_s, cov, dt_s, inverse_depth};  // before the latency terms
  if (!paper_noise_) {
    const Matrix6d depth_response = latency_.depth_s > 0 ? covariance_.depth_latency_response(inlier_prev_, inlier_curr_)
                                                         : Matrix6d::Zero();
    cov += config_.covariance.scale * latency_covariance(latency_, depth_response, own, last_pair_);
  }
  last_pair_ = own;
}

}  // namespace rgbdo
