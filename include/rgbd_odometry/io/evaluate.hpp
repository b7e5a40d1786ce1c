#pragma once
// Accuracy against motion-capture ground truth: frame-to-frame relative pose error (RPE),
// drift over 1-second windows of the integrated trajectory, and the covariance's
// consistency as the normalised estimation error squared (NEES; 6 on average when the
// reported covariance matches the real error).
#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "rgbd_odometry/core/pair_result.hpp"
#include "rgbd_odometry/io/tum_sequence.hpp"

namespace rgbdo {

struct ErrorStats {
  int count = 0;
  double rmse = 0, median = 0, max = 0;
};
ErrorStats error_stats(std::vector<double> values);

struct AccuracySummary {
  int pairs = 0;
  int failed = 0;
  std::map<std::string, int> failures;  // status word -> count
  int evaluated = 0;                   // ok pairs with ground truth at both ends
  ErrorStats rpe_translation_m, rpe_rotation_deg;
  ErrorStats drift_translation_mps, drift_rotation_degps;  // over 1-second windows
  double mean_nees = 0, median_nees = 0;
  double nees_within_95 = 0;  // fraction of pairs with NEES below chi2_6(0.95) = 12.59
  // Per-axis consistency of the diagonal (what EKF2/EKF3 fuse): mean of e_i^2 / C_ii over
  // pairs, for xi = (tx, ty, tz, rx, ry, rz); 1 when the variances match the errors.
  Eigen::Matrix<double, 6, 1> axis_nees = Eigen::Matrix<double, 6, 1>::Zero();
  double mean_axis_nees = 0;
  // The covariance.scale that would have made mean_axis_nees equal 1, given the one used.
  double consistent_scale = 0;
};

class AccuracyEvaluator {
 public:
  AccuracyEvaluator(const GroundTruth& groundtruth, double covariance_scale_used);
  // Pairs in order; `pose` is the integrated pose of the pair's current frame.
  void add(const PairResult& r, const Eigen::Isometry3d& pose);
  AccuracySummary summary() const;
  bool has_groundtruth() const { return !groundtruth_.empty(); }

 private:
  const GroundTruth& groundtruth_;
  double scale_used_;
  int pairs_ = 0;
  std::map<std::string, int> failures_;
  std::vector<double> rpe_t_, rpe_r_, nees_;
  Eigen::Matrix<double, 6, 1> axis_nees_sum_ = Eigen::Matrix<double, 6, 1>::Zero();
  std::vector<std::pair<std::int64_t, Eigen::Isometry3d>> trajectory_;
};

}  // namespace rgbdo
