#pragma once
// The per-pair half of the pipeline: match -> 3-D point pairs -> RANSAC -> covariance, on two
// frames already through FrameExtractor. Its state lives as long as the pair stream: scratch
// buffers sized once (no allocation per pair) and the last pair's rate: the motion prior for
// the matching window and colour/depth timing compensation of the next, and the start of the
// change of rate its latency terms see.
#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "rgbd_odometry/pipeline/pipeline_config.hpp"
#include "rgbd_odometry/core/pair_result.hpp"
#include "rgbd_odometry/pipeline/backproject.hpp"
#include "rgbd_odometry/pipeline/capture_latency.hpp"
#include "rgbd_odometry/pipeline/covariance.hpp"
#include "rgbd_odometry/pipeline/depth_alignment.hpp"
#include "rgbd_odometry/pipeline/depth_clock.hpp"
#include "rgbd_odometry/pipeline/keypoint_sigma.hpp"
#include "rgbd_odometry/pipeline/frame_extractor.hpp"
#include "rgbd_odometry/pipeline/latency_covariance.hpp"
#include "rgbd_odometry/pipeline/match.hpp"
#include "rgbd_odometry/pipeline/ransac.hpp"
#include "rgbd_odometry/pipeline/stamp_jitter.hpp"
#include "rgbd_odometry/pipeline/track.hpp"

namespace rgbdo {

class PairEstimator {
 public:
  explicit PairEstimator(const PipelineConfig& config);  // config must have passed validate()

  // The pair's random streams are seeded from the two frames' content and config.seed: the
  // same two frames give the same result in any run, at any place in it.
  // The caller drops curr and pairs the next frame with prev (dropped_frame() says so) when curr
  // was captured no later than prev (Status::StampNotIncreasing), or has no depth (NoDepth) while
  // prev is good and at most kMaxBridgedGapNs before it: the motion is carried across the frame
  // without depth by the next pair, nothing is lost, and the estimator's state is untouched.
  [[nodiscard]] PairResult estimate(const ProcessedFrame& prev, const ProcessedFrame& curr);
  static bool dropped_frame(const PairResult& r) { return r.frame_dropped; }
  // How far a frame without depth may be from the last good one and still be bridged. Beyond
  // it the last velocity predicts little, and the flight controller is told tracking is lost
  // (failed pairs) rather than hear nothing.
  static constexpr std::int64_t kMaxBridgedGapNs = 200'000'000;

  // The streams' latencies, where they are measured against the autopilot's gyro
  // (pipeline/capture_latency.hpp): what is left of each replaces covariance.colour_latency_sigma_s
  // and depth_latency_sigma_s in the pairs' latency terms (latency_covariance.hpp); nullopt: that
  // prior.
  void set_latency_sigmas(const MeasuredLatencySigmas& measured) {
    latency_.colour_s = measured.colour_s.value_or(config_.covariance.colour_latency_sigma_s);
    latency_.depth_s = measured.depth_s.value_or(config_.covariance.depth_latency_sigma_s);
    latency_.translation_s = measured.translation_s.value_or(0);
    applied_s_ = measured.applied_s;
    latency_.image_shift_off_s =
        measured.image_shift_retime_s ? measured.image_shift_retime_sigma_s : measured.applied_s;
    latency_.image_shift_retime_s = measured.image_shift_retime_s.value_or(0);  // depth_clock.hpp carries it
    rotations_timed_ = measured.gyro;
  }

  // A gap in the frames (sensor lost): the last pair's velocity no longer predicts the next.
  void forget_motion() {
    last_pair_.reset();
    last_feature_pair_.reset();
    depth_clock_.forget();
  }

 private:
  // The steps of estimate(), in order.
  // The features' first fit into fit_: within the window the last pair's motion predicts,
  // again over all pairs when that fails or finds too few inliers.
  Status fit_features(const ProcessedFrame& prev, const ProcessedFrame& curr, double dt_s, bool compensate,
                      std::uint64_t pair_key, PairResult& r);
  // The matched keypoints tracked below a pixel and fit_ refined on them (and on the depths
  // carried with this pair's own motion); the current keypoints' geometry the rest uses.
  const KeypointGeometry& track_and_refit(const ProcessedFrame& prev, const ProcessedFrame& curr, double dt_s,
                                          bool compensate, PairResult& r);
  // fit_'s covariance from the perturbed inliers; false: it could not be estimated.
  bool features_covariance(const ProcessedFrame& prev, const ProcessedFrame& curr,
                           const KeypointGeometry& curr_geometry, double dt_s, std::uint64_t pair_key,
                           Matrix6d& cov);
  // refine_with_depth with what the pair reports of it and the features' rate kept.
  void fuse_depth_alignment(const ProcessedFrame& prev, const ProcessedFrame& curr, double dt_s, bool learn,
                            const Vector6d& features_xi, Matrix6d& cov, PairResult& r);
  // The capture latencies' terms (latency_covariance.hpp) added to cov; this pair becomes last_pair_.
  void add_latency_terms(double dt_s, Matrix6d& cov);

  // Matching (within the window window_prior predicts, or over all pairs when null), 3-D
  // point pairs (depths carried to colour time with timing_prior, unless null) and RANSAC's
  // first fit into fit_; fills r's counts and adds to its times.
  Status match_and_fit(const ProcessedFrame& prev, const ProcessedFrame& curr, const MotionPrior* window_prior,
                       double dt_s, const MotionPrior* timing_prior, std::uint64_t pair_key, PairResult& r);

  // `frame`'s keypoint's pyramid level, within ORB's levels.
  int keypoint_level(const ProcessedFrame& frame, size_t keypoint) const;
  // The noise of point p, measured at `frame`'s keypoint: the covariance's model (its level's
  // law, its depth slope; no timing term), and the covariance RANSAC's final fit weighs it by
  // (its level's learnt localisation, fit_weight_noise).
  PointNoise keypoint_noise(const ProcessedFrame& frame, size_t keypoint, const Eigen::Vector3d& p) const;
  Eigen::Matrix3d fit_covariance(const ProcessedFrame& frame, size_t keypoint, const Eigen::Vector3d& p) const;
  // Each point pair's covariances (pair_covariances_) for RANSAC's final fit.
  void describe_pair_noise(const ProcessedFrame& prev, const ProcessedFrame& curr);
  // The current keypoints of every point pair moved to where the previous keypoints' patches
  // lie (tracked_); how many moved.
  int track_keypoints(const ProcessedFrame& prev, const ProcessedFrame& curr);
  // The keypoints' localisation learnt from fit_'s inliers' reprojection residuals, curr_geometry
  // the current keypoints' (tracked or as detected).
  void learn_keypoint_sigma(const ProcessedFrame& prev, const ProcessedFrame& curr,
                            const KeypointGeometry& curr_geometry);
  // The noise and image cell of each inlier (inlier_prev_noise_, inlier_curr_noise_,
  // inlier_cells_) for the covariance.
  void describe_inlier_noise(const ProcessedFrame& prev, const ProcessedFrame& curr,
                             const KeypointGeometry& curr_geometry, double dt_s);

  // The depth maps' alignment, started at fit_'s motion, fused with it: fit_'s motion and
  // `covariance` (of xi, the features') become the fused ones. The number of depth points
  // used, 0 when the alignment failed or disagreed (then nothing changes); depth_trusted: it
  // was fused at the learnt factors rather than at refinement.distrusted_sigma_scale.
  // learn: whether this pair may update the learnt sensor constants (see its use).
  int refine_with_depth(const ProcessedFrame& prev, const ProcessedFrame& curr, double dt_s, bool learn,
                        Matrix6d& covariance, bool& depth_trusted);

  PipelineConfig config_;
  bool paper_noise_;  // covariance.model "paper", decided once
  SensorNoise noise_;
  SensorNoise fit_noise_;  // the final fit's weights (fit_weight_noise)
  std::array<double, KeypointSigmaEstimate::kMaxLevels> fit_sigma_px_{};  // each level's, in_weight_steps
  bool tracking_;  // matching.subpixel_tracking, never with the paper's model
  SymmetricMatcher matcher_;
  SubpixelTracker tracker_;
  KeypointGeometry tracked_;  // the current frame's geometry, its matched keypoints tracked
  RigidRansac ransac_;
  PerturbationCovariance covariance_;
  DepthAligner aligner_;
  DepthAlignment alignment_;
  AlignmentTrust alignment_trust_;
  DepthLagEstimate depth_lag_;
  DepthClock depth_clock_;  // the depth's lag carried out of the motion (optical axis, tilt)
  bool rotations_timed_ = false;  // a gyro times the rotations (set_latency_sigmas)
  double applied_s_ = 0;             // the latency the pairs' stamps are moved by (set_latency_sigmas)
  DepthNoiseEstimate depth_noise_;
  KeypointSigmaEstimate keypoint_sigma_;
  std::vector<Match> matches_;
  std::vector<Eigen::Vector2d> predicted_;  // previous keypoints' positions in the current frame
  PointPairs pairs_;
  PointPairCovariances pair_covariances_;  // of pairs_, the physical model's (empty for the paper's)
  RansacResult fit_, refined_;
  std::vector<Eigen::Vector3d> inlier_prev_, inlier_curr_;
  std::vector<PointNoise> inlier_prev_noise_, inlier_curr_noise_;
  std::vector<std::uint16_t> inlier_cells_;  // image cell of each inlier (current frame)
  StampJitter stamp_jitter_;
  LatencySigmas latency_;
  // The last good pair: its velocity is the motion prior for matching and timing
  // compensation; its rate and covariance (before its latency terms) feed the next's.
  std::optional<PairRate> last_pair_;
  // The same pair's features alone, before any fusion with the depth alignment: the depth's lag
  // is read against their change of rate, which the alignment fused into them would bias.
  std::optional<PairRate> last_feature_pair_;
  // This pair's depth alignment's own rotation, over the depth frames' interval (refine_with_depth).
  std::optional<Eigen::Vector3d> depth_rotation_;
};

}  // namespace rgbdo
