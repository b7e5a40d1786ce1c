#pragma once
// The covariance that goes out with each motion (the log, ODOMETRY's velocity covariance):
// the pair's own, its level and shape followed over a short time rather than pair by pair.
//
// From pair to pair the estimated covariance spans 2.5-3.6x in σ (90th over 10th percentile),
// but only part of that spread is the error's: in the frame a flight controller keeps (its
// diagonal, in the world) the slope of log |error| on log σ is 0.13-0.75 for the level and
// about 0 for the shape (bench/MEASUREMENTS.md#with-keyframes-what-the-filter-integrates). A
// filter weighs each motion by it: weights that vary without the error spoil the equal-weight
// average over which the consecutive errors partly cancel, and a few pairs that claim a
// precision they do not have pull its velocity. What goes out is therefore a running mean,
// over smoothing_s, of the rate covariance (the pair's over dt^2) in the log-Euclidean metric
// (the matrix logarithm's mean: a geometric mean, which leaves a covariance's consistency as
// it found it where the arithmetic mean of matrices would inflate it), back at the pair's dt.
// Where a pair's own covariance is wider than that (too few inliers, features starving), it
// weighs in from sqrt(pass_ratio) times as wide and goes out as its own from pass_ratio: the
// mean must not hide a sudden loss.
// Measured: src/pipeline/MEASUREMENTS.md#what-goes-out-the-level-over-a-second.
#include "rgbd_odometry/core/geometry.hpp"
#include "rgbd_odometry/core/pair_result.hpp"
#include "rgbd_odometry/pipeline/pipeline_config.hpp"

namespace rgbdo {

class ReportedCovariance {
 public:
  // covariance.smoothing_s <= 0: each pair's own covariance goes out unchanged.
  explicit ReportedCovariance(const CovarianceConfig& config)
      : smoothing_s_(config.smoothing_s), pass_ratio_(config.smoothing_pass_ratio) {}

  // Replaces a good pair's covariance with what is reported for it; a failed pair passes
  // through, and after a lost sensor the mean starts again.
  void report(PairResult& pair);

 private:
  double smoothing_s_, pass_ratio_;
  bool started_ = false;
  Matrix6d mean_log_ = Matrix6d::Zero();  // of the rate covariance
};

}  // namespace rgbdo
