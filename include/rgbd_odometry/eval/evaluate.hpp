#pragma once
// Accuracy against motion-capture ground truth: frame-to-frame relative pose error (RPE),
// drift over 1-second windows of the integrated trajectory, and the covariance's
// consistency, always with the ground truth's own noise allowed for (groundtruth_noise.hpp):
//  - per pair, the normalised estimation error squared NEES = e^T (C + A)^-1 e (chi2(6):
//    mean 6, 95 % below 12.59, when C is right), per axis e_i^2 / (C_ii + A_ii) and the
//    fraction within 3 sigma;
//  - over 1-second windows, the motions composed and their covariances propagated to first
//    order with the SE(3) adjoint as independent errors: what a filter integrating the
//    velocities believes; errors correlated between pairs show here and not per pair;
//  - the lag-1 correlation of consecutive pairs' errors, per axis;
//  - the time offsets between the frames' stamps and the ground truth's clock that match the
//    rotations (colour) and tz (depth) best: the streams' capture-to-stamp latencies, or the
//    reference's own time alignment. A lag
//    shows as errors that follow the change of the motion (angular acceleration x lag x dt),
//    correlated between consecutive pairs and growing with the frame interval.
#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "rgbd_odometry/core/pair_result.hpp"
#include "rgbd_odometry/eval/groundtruth_noise.hpp"
#include "rgbd_odometry/io/tum_sequence.hpp"

namespace rgbdo {

struct ErrorStats {
  int count = 0;
  double rmse = 0, median = 0, max = 0;
};
ErrorStats error_stats(std::vector<double> values);

struct NeesStats {
  int count = 0;
  double mean = 0, median = 0;
  double within_95 = 0;  // fraction below chi2_6(0.95) = 12.59
};
NeesStats nees_stats(std::vector<double> values);

using Vector6 = Eigen::Matrix<double, 6, 1>;

// The offset tau (frames taken tau before their stamps, tau < 0: after) for which the ground
// truth between the shifted stamps matches one part of the estimated motions best, searched
// over +-max_offset_s; not found at the edge of the search or with too few pairs. Fitted on the
// rotations (driven by the colour images' features) and, apart, on the translation along the
// optical axis (driven by the depth images): the two streams' latencies.
struct TimeOffsetFit {
  bool found = false;
  double offset_s = 0;
  double max_offset_s = 0;
  int pairs = 0;               // pairs whose ground truth covers every offset tried
  double rmse_at_stamps = 0;   // of the fitted part (rad or m) over those pairs
  double rmse_at_offset = 0;
  // Of offset_s, as a least-squares fit of one parameter over independent pairs would have it
  // (the cost's curvature at the minimum against its level); 0 when not found.
  double standard_error_s = 0;
};

struct AccuracySummary {
  int pairs = 0;
  int failed = 0;
  std::map<std::string, int> failures;  // status word -> count
  int evaluated = 0;                   // ok pairs with ground truth at both ends
  ErrorStats rpe_translation_m, rpe_rotation_deg;
  ErrorStats drift_translation_mps, drift_rotation_degps;  // over 1-second windows
  GroundTruthAllowance allowance;
  NeesStats pair_nees, window_nees;
  // Per axis of xi = (tx, ty, tz, rx, ry, rz): mean of e_i^2 / (C_ii + A_ii) (1 when the
  // variances match the errors: what EKF2/EKF3 fuse) and the fraction within 3 sigma.
  Vector6 axis_nees = Vector6::Zero();
  Vector6 axis_within_3sigma = Vector6::Zero();
  Vector6 lag1_correlation = Vector6::Zero();  // of consecutive pairs' errors
  int lag1_pairs = 0;
  // Per axis over the 1-s windows, as axis_nees per pair: which axes' errors persist.
  Vector6 window_axis_nees = Vector6::Zero();
  TimeOffsetFit rotation_time_offset;  // the colour stream's
  TimeOffsetFit depth_time_offset;     // of tz: the depth stream's
};

// One evaluated pair, for plots (the evaluation CSV).
struct EvaluatedPair {
  std::int64_t t_ns = 0;                    // the pair's current frame
  Vector6 error = Vector6::Zero();           // xi(estimate) - xi(ground truth)
  Vector6 sigma = Vector6::Zero();           // sqrt of the reported variances (no allowance)
  double nees = 0;
  double window_nees = -1;                   // of the 1-s window ending here; < 0: none
  Eigen::Vector3d position = Eigen::Vector3d::Zero();               // integrated
  Eigen::Vector3d groundtruth_position = Eigen::Vector3d::Zero();   // same origin
};

class AccuracyEvaluator {
 public:
  AccuracyEvaluator(const GroundTruth& groundtruth, GroundTruthAllowance allowance);
  // Pairs in order; `pose` is the integrated pose of the pair's current frame.
  void add(const PairResult& r, const Eigen::Isometry3d& pose);
  AccuracySummary summary() const;
  bool has_groundtruth() const { return !groundtruth_.empty(); }
  // Rows of the evaluated pairs (window NEES filled in by summary's computation).
  std::vector<EvaluatedPair> evaluated_pairs() const;
  // Writes them as CSV (header documents the columns); throws std::runtime_error naming the file.
  void write_csv(const std::string& path) const;

 private:
  struct Step {  // every pair, in order, as the window composition needs them
    std::int64_t t_prev_ns, t_curr_ns;
    bool ok;
    Eigen::Isometry3d T;
    Matrix6d covariance;
  };
  Matrix6d allowance_covariance() const;
  struct Window {
    size_t first, last;  // indices in steps_ of its first and last pair
    double nees;
    Vector6d axis_ratio;  // e_i^2 / var_i
  };
  // Every 1-s window: from each pair, the shortest run of consecutive good pairs spanning 1 s.
  std::vector<Window> windows() const;
  // The good pairs whose ground truth covers every shift tried (subsampled for long runs), so
  // that each shift is judged on the same pairs.
  std::vector<const Step*> time_offset_pairs() const;
  enum class OffsetFitPart { Rotation, OpticalAxisTranslation };
  TimeOffsetFit fit_time_offset(const std::vector<const Step*>& pairs, OffsetFitPart part) const;

  const GroundTruth& groundtruth_;
  GroundTruthAllowance allowance_;
  int pairs_ = 0;
  std::map<std::string, int> failures_;
  std::vector<double> rpe_t_, rpe_r_;
  std::vector<Step> steps_;
  std::vector<EvaluatedPair> evaluated_;
  std::vector<size_t> evaluated_step_;  // index in steps_ of each evaluated pair
  std::vector<std::pair<std::int64_t, Eigen::Isometry3d>> trajectory_;
  std::optional<Eigen::Isometry3d> groundtruth_origin_;  // ground truth of the first frame
};

}  // namespace rgbdo
