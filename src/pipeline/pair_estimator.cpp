#include "rgbd_odometry/pipeline/pair_estimator.hpp"

#include <chrono>

#include "rgbd_odometry/core/clock.hpp"
#include "rgbd_odometry/core/cost_stage.hpp"
#include "rgbd_odometry/core/noise_model.hpp"
#include "rgbd_odometry/core/splitmix64.hpp"

namespace rgbdo {
namespace {

using Clock = std::chrono::steady_clock;

MotionPrior motion_from(const Eigen::Isometry3d& T_prev_curr, double dt_s) {
  MotionPrior m;
  m.velocity_mps = T_prev_curr.translation() / dt_s;
  m.angular_velocity_radps = rotation_vector(T_prev_curr.linear()) / dt_s;
  return m;
}

// Decorrelates the per-pair random streams while keeping every pair replayable from the seed:
// the (index + 1)-th output of a splitmix64 generator started at the seed.
std::uint64_t mix(std::uint64_t seed, std::uint64_t index) {
  return splitmix64_mix(seed + kSplitMix64Increment * (index + 1));
}

}  // namespace

PairEstimator::PairEstimator(const Config& config)
    : config_(config),
      matcher_(config.matching.ratio),
      ransac_(config.ransac, sensor_noise(config), config.features.max_features),
      covariance_(config.covariance, config.features.max_features) {
  // Sized once for the largest possible frame: the pair stage never allocates afterwards.
  const auto capacity = static_cast<size_t>(config.features.max_features);
  matches_.reserve(capacity);
  for (auto* v : {&pairs_.prev, &pairs_.curr, &inlier_prev_, &inlier_curr_}) v->reserve(capacity);
  pairs_.match_index.reserve(capacity);
  fit_.inliers.reserve(capacity);
  refined_.inliers.reserve(capacity);
}

PairResult PairEstimator::estimate(const ProcessedFrame& prev, const ProcessedFrame& curr, std::uint64_t pair_index) {
  PairResult r;
  r.t_prev_ns = prev.times.t_colour_ns;
  r.t_curr_ns = curr.times.t_colour_ns;
  r.features_prev = static_cast<int>(prev.features.keypoints.size());
  r.features_curr = static_cast<int>(curr.features.keypoints.size());
  const auto fail = [&](Status s) {
    r.status = s;
    last_motion_.reset();  // a gap: the old velocity says nothing about the next pair
    return r;
  };
  // The newer frame's problem is the news; the older one's was reported with its own pair.
  if (curr.status != Status::Ok) return fail(curr.status);
  if (prev.status != Status::Ok) return fail(prev.status);
  const double dt_s = static_cast<double>(r.t_curr_ns - r.t_prev_ns) * 1e-9;

  const CostStagesEnd stages_end;
  mark_cost_stage(CostStage::Match);
  auto t0 = Clock::now();
  matcher_.match(prev.features.descriptors, curr.features.descriptors, matches_);
  r.matches = static_cast<int>(matches_.size());
  r.times.match_ms = ms_since(t0);
  if (r.matches < config_.ransac.min_inliers) return fail(Status::TooFewMatches);

  const bool compensate = config_.depth.compensate_timing && dt_s > 0;
  // Before this pair is solved, the previous pair's velocity is the best guess (zero after a gap).
  const MotionPrior prior = last_motion_.value_or(MotionPrior{});
  mark_cost_stage(CostStage::PointPairs);
  t0 = Clock::now();
  build_point_pairs(matches_, prev.geometry, prev.times, curr.geometry, curr.times, compensate ? &prior : nullptr,
                    pairs_);
  r.point_pairs = static_cast<int>(pairs_.size());
  r.times.backproject_ms = ms_since(t0);
  if (r.point_pairs < config_.ransac.min_inliers) return fail(Status::TooFewMatches);

  // Separate streams: the covariance's noise must not depend on how many draws RANSAC used.
  Rng ransac_rng(mix(config_.seed, 2 * pair_index));
  Rng covariance_rng(mix(config_.seed, 2 * pair_index + 1));
  mark_cost_stage(CostStage::Ransac);
  t0 = Clock::now();
  ransac_.estimate(pairs_.prev, pairs_.curr, ransac_rng, fit_);
  r.times.ransac_ms = ms_since(t0);
  if (fit_.status != Status::Ok) return fail(fit_.status);

  if (compensate) {
    // Second pass: carry the depths to colour time with this pair's own velocity, which is
    // better than the previous pair's whenever the depth frames are far enough apart.
    mark_cost_stage(CostStage::PointPairs);
    t0 = Clock::now();
    const MotionPrior own = motion_from(fit_.T_prev_curr, dt_s);
    build_point_pairs(matches_, prev.geometry, prev.times, curr.geometry, curr.times, &own, pairs_);
    r.times.backproject_ms += ms_since(t0);
    mark_cost_stage(CostStage::Ransac);
    t0 = Clock::now();
    ransac_.refine(pairs_.prev, pairs_.curr, fit_.T_prev_curr, refined_);
    r.times.ransac_ms += ms_since(t0);
    if (refined_.status == Status::Ok) {
      refined_.hypotheses = fit_.hypotheses;
      std::swap(fit_, refined_);  // swaps buffers, allocates nothing
    }
  }

  mark_cost_stage(CostStage::Covariance);
  inlier_prev_.clear();
  inlier_curr_.clear();
  for (int k : fit_.inliers) {
    inlier_prev_.push_back(pairs_.prev[static_cast<size_t>(k)]);
    inlier_curr_.push_back(pairs_.curr[static_cast<size_t>(k)]);
  }
  t0 = Clock::now();
  Matrix6d cov;
  const bool cov_ok = covariance_.estimate(inlier_prev_, inlier_curr_, fit_.T_prev_curr, covariance_rng, cov);
  r.times.covariance_ms = ms_since(t0);
  if (!cov_ok) return fail(Status::CovarianceFailed);

  r.status = Status::Ok;
  r.inliers = static_cast<int>(fit_.inliers.size());
  r.inlier_threshold_m = fit_.threshold_m;
  r.T_prev_curr = fit_.T_prev_curr;
  r.covariance = cov;
  if (dt_s > 0) last_motion_ = motion_from(fit_.T_prev_curr, dt_s);
  return r;
}

}  // namespace rgbdo
