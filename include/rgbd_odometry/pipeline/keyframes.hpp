#pragma once
// Keyframes: every frame is measured against a kept earlier frame as well as against the one
// before it, so that a camera over one view reports the same place every time it comes back.
//
// Frame to frame, each pair's error is new and the pose walks: a drone swaying over one view
// drifts a little every sway, and a still one does too. Here the pose of each frame relative
// to its keyframe is predicted by the frame pair (its motion, as PairEstimator made it), then
// measured against the keyframe: the frame's features matched with the keyframe's within the
// window the prediction sets, the keyframe's patches tracked into the frame, the prediction
// refined over those 3-D pairs (RigidRansac::refine), and where the pair stage trusts the depth
// the two depth maps aligned as well. Where the two agree, the pose moves keyframes.gain of the
// way to the measurement: the frame pairs keep the short term, the keyframe the long, and over
// one view the pose stays near where it was. (The gain the covariances would give trusts the
// keyframe far too much on a Kinect: src/pipeline/README.md#keyframes.)
//
// A new keyframe when the inliers against the current one fall below a share of its first
// frame's; before one is made, the most overlapping of the few kept is tried, so that a return
// to an earlier view re-attaches to it. A switch is not a reset: the chain goes on.
//
// What goes out: each pair's motion becomes the motion between the two frames' anchored poses,
// so that integrating the pairs gives the anchored trajectory. Its covariance stays the frame
// pair's (see src/pipeline/README.md for what a consumer may assume of consecutive pairs); the
// pose's since the chain began goes out in PairResult::keyframe, for ODOMETRY's pose.
//
// The keyframe's features, descriptors, image and depth cloud are kept, not recomputed: the
// measurement costs a windowed match, the sub-pixel tracking of the matched keypoints (without
// it a measurement on exact depth errs 2.5 mm where the pair errs 0.7), one refinement and, on
// trusted depth, one alignment. The kept frames' buffers are sized at construction: nothing is
// allocated per frame (for frames of the configured size).
#include <Eigen/Geometry>
#include <cstdint>
#include <span>
#include <vector>

#include "rgbd_odometry/core/geometry.hpp"
#include "rgbd_odometry/core/pair_result.hpp"
#include "rgbd_odometry/pipeline/backproject.hpp"
#include "rgbd_odometry/pipeline/depth_alignment.hpp"
#include "rgbd_odometry/pipeline/frame_extractor.hpp"
#include "rgbd_odometry/pipeline/match.hpp"
#include "rgbd_odometry/pipeline/noise_model.hpp"
#include "rgbd_odometry/pipeline/pipeline_config.hpp"
#include "rgbd_odometry/pipeline/ransac.hpp"
#include "rgbd_odometry/pipeline/track.hpp"

namespace rgbdo {

// A frame's keypoints as 3-D points at its colour instant: the depth carried from the depth
// frame's instant with the camera's motion (backproject.hpp), z = 0 where there is no depth.
void anchored_points(const KeypointGeometry& geometry, const FrameTimes& times, const MotionPrior* motion,
                     double fx, double fy, std::vector<Eigen::Vector3d>& out);

// The covariance of the right perturbation of T (prev ~ T curr) fitted to the inlier pairs by
// least squares under the point covariances, to first order, scaled by the fit's a-posteriori
// variance factor (at least 1) as the perturbation covariance is, and raised to the
// cluster-robust covariance over the pairs' image cells (cells[k] of pair k; empty: none)
// along every direction where that is larger.
Matrix6d rigid_fit_covariance(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                              const std::vector<int>& inliers, const PointPairCovariances& covariances,
                              std::span<const int> cells, const Eigen::Isometry3d& T);

class KeyframeTracker {
 public:
  explicit KeyframeTracker(const PipelineConfig& config);  // config must have passed validate()

  // After PairEstimator made `pair` (previous frame, curr): curr measured against the keyframe
  // and pair.T_prev_curr replaced by the motion between the two frames' anchored poses (its
  // covariance is left as it is); pair.keyframe says what happened. A failed pair ends the
  // chain of keyframes: the next good pair starts a new one.
  void update(const ProcessedFrame& curr, PairResult& pair);

 private:
  // The covariance of a right perturbation along the chain: a bound that holds whatever its
  // errors share, for the pull's prediction and measurement share them by an amount no frame
  // shows (every measurement against one keyframe carries that keyframe's own noise, the
  // prediction has been pulled towards the earlier ones, and consecutive frame pairs err alike
  // while the camera keeps moving one way). Two rules make it one:
  //  - the pull, (1-g) P + g R (Cov((1-g) a + g b) = (1-g) Cov(a) + g Cov(b) - g(1-g) Cov(a-b));
  //  - a frame pair's step added to the chain: (1+a) P + (1+1/a) S for any a > 0 bounds
  //    Cov(e_P + e_S) (the cross term, 2 Cov(e_P, e_S) <= a P + S/a), a = sqrt(tr S / tr P)
  //    making it the smallest in trace.
  // The gates judge measurements by it too. Kept as if the errors were independent, the chain
  // claimed a third of its error along the slide between sideways translation and rotation (a
  // noisy sway over ICL-NUIM with averaged depth: 1.6 mm against a sigma of 0.2-0.6), failed the
  // gate on measurements that were right, and made keyframes at the wrong pose instead (2 to 10
  // made, up to 9.4 mm from the start after 10 sways; src/pipeline/MEASUREMENTS.md, "The chain's
  // covariance: a bound whatever its errors share").
  static Matrix6d carried(const Matrix6d& chain, const Matrix6d& adjoint) { return adjoint * chain * adjoint.transpose(); }
  static Matrix6d extended(const Matrix6d& chain, const Matrix6d& step);
  struct Keyframe {
    Features features;
    KeypointGeometry geometry;
    cv::Mat gray;                         // for the sub-pixel tracker (empty when it is off)
    DepthCloud cloud;                     // for the depth alignment (empty when it is off)
    std::vector<Eigen::Vector3d> points;  // anchored_points of its keypoints
    std::vector<int> levels;              // each keypoint's pyramid level
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // in the trajectory's frame
    Matrix6d pose_covariance = Matrix6d::Zero();             // of its right perturbation
    bool live = false;          // holds a keyframe of the current chain
    int reference_inliers = 0;  // its first measured frame's; 0: none yet
    std::uint64_t id = 0;
    std::uint64_t last_used = 0;
    FrameTimes times;  // its capture times (the depth alignment needs colour and depth together)
    Eigen::Isometry3d depth_shift = Eigen::Isometry3d::Identity();  // PairResult::depth_shift
  };
  struct Measurement {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();  // curr in the keyframe's frame
    Matrix6d covariance = Matrix6d::Zero();                 // of its right perturbation
    int inliers = 0;
  };

  // curr against kf, starting from the prediction T_pred: false when too few pairs or inliers,
  // or, where the depth is aligned, too few to hold kf.
  bool measure(const Keyframe& kf, const ProcessedFrame& curr, const Eigen::Isometry3d& T_pred, Measurement& out);
  // Whether the pair stage trusts the sensor's depth (PairResult::depth_trusted) and both
  // frames' depth and colour were taken together (the alignment measures the motion between
  // the depth instants).
  bool depth_alignable(const Keyframe& kf, const ProcessedFrame& curr) const;
  // The two depth maps' alignment, started at out.T, fused into out.
  void refine_with_depth(const Keyframe& kf, const ProcessedFrame& curr, Measurement& out);
  // Whether the measurement agrees with the prediction (chi^2 gate of fuse_estimates).
  bool agree(const Eigen::Isometry3d& T_pred, const Matrix6d& cov_pred, const Measurement& z) const;
  // T_kf_curr_ and its covariance: the prediction moved a keyframes.gain share of the way to z.
  void correct(const Eigen::Isometry3d& T_pred, const Matrix6d& cov_pred, const Measurement& z);
  // Whether a measurement with `inliers` still holds kf.
  bool holds(const Keyframe& kf, int inliers) const;
  // The kept keyframe (not `except`) that sees most of its points in curr from pose_, or -1.
  int most_overlapping(int except) const;
  void make_keyframe(const ProcessedFrame& curr);
  Matrix6d pose_covariance() const;  // of pose_'s right perturbation

  PipelineConfig config_;
  SensorNoise noise_;
  bool tracking_;  // tracks_keypoints(config)
  SymmetricMatcher matcher_;
  SubpixelTracker tracker_;
  RigidRansac ransac_;
  DepthAligner aligner_;
  DepthAlignment alignment_;
  // The pair stage's verdict on the depth, and its learnt factors (PairResult::sensor).
  bool depth_trusted_ = false;
  double depth_scale_t_ = 1, depth_scale_r_ = 1;
  std::vector<Keyframe> kept_;  // keyframes.kept slots, their buffers sized at construction
  int active_ = -1;  // index into kept_; -1: no chain
  std::uint64_t next_id_ = 1, frames_ = 0;
  Eigen::Isometry3d T_kf_curr_ = Eigen::Isometry3d::Identity();  // the last frame in the active keyframe's
  Matrix6d cov_kf_curr_ = Matrix6d::Zero();                       // of its right perturbation
  Eigen::Isometry3d pose_ = Eigen::Isometry3d::Identity();        // the last frame in the trajectory's frame
  // The current frame's motion, its depths are carried to its colour instant with (null: not).
  MotionPrior own_motion_;
  Eigen::Isometry3d curr_depth_shift_ = Eigen::Isometry3d::Identity();  // the current frame's (PairResult::depth_shift)
  const MotionPrior* motion_ = nullptr;
  // Per-frame scratch, sized once.
  std::vector<Eigen::Vector3d> curr_points_;
  std::vector<Eigen::Vector2d> predicted_;
  std::vector<Match> matches_;
  std::vector<int> usable_;                // the matches with depth in both frames
  KeypointGeometry tracked_;               // the current frame's, its matched keypoints tracked
  std::vector<Eigen::Vector3d> tracked_points_;
  std::vector<Eigen::Vector3d> pair_kf_, pair_curr_;
  PointPairCovariances pair_covariances_;
  std::vector<int> pair_cells_;  // each pair's image cell in the current frame (covariance.resample_cell_px)
  RansacResult fit_;
};

}  // namespace rgbdo
