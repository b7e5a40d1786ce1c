#pragma once
// What the pipeline says about one pair of consecutive frames: the contract between the
// estimator (pipeline/) and everything downstream of it (io/ logs and evaluation, link/
// messages, runtime/ and app/), which is why it lives in core/ and needs only Eigen.
#include <Eigen/Geometry>
#include <cstdint>
#include <limits>

#include "rgbd_odometry/core/geometry.hpp"
#include "rgbd_odometry/core/sensor_estimates.hpp"
#include "rgbd_odometry/core/status.hpp"

namespace rgbdo {

struct StageTimes {  // wall time of each stage for this pair, milliseconds
  double detect_ms = 0;       // mask + detection + description + keypoint geometry, current frame
  double match_ms = 0;
  double backproject_ms = 0;  // building the 3-D pairs (incl. the timing-compensation pass)
  double ransac_ms = 0;
  double covariance_ms = 0;
  double keyframe_ms = 0;     // the frame measured against its keyframe (pipeline/keyframes.hpp)
};

// The current frame's keyframe (pipeline/keyframes.hpp).
struct KeyframeLink {
  std::uint64_t id = 0;  // 0: none (keyframes off, or the pair failed)
  int inliers = 0;       // the frame's inliers against it; 0: not measured (a new keyframe, or none held)
  bool created = false;  // the frame became a new keyframe
  bool returned = false; // the frame re-attached to an earlier keyframe
  // The chain of keyframes began at this frame: the first good pair, or the first after a
  // failed one (an unknown motion ends a chain).
  bool chain_started = false;
  // The covariance of the right perturbation of this frame's pose relative to the frame the
  // chain began at (camera frame, xi = (t, rotvec)): what the keyframes leave of the error
  // since then. Over one view it stays put where integrated pairs would grow frame by frame.
  Matrix6d pose_covariance = Matrix6d::Zero();
};

struct PairResult {
  // Capture times of the two frames' colour images: their stamps, or, where the latency is
  // measured against the autopilot's gyro, the stamps less the latency (timing.applied_s).
  std::int64_t t_prev_ns = 0;
  std::int64_t t_curr_ns = 0;
  Status status = Status::Ok;
  // The newer frame was dropped (status says why: StampNotIncreasing, or NoDepth bridged): no
  // motion, nothing sent; the next frame pairs with the older one.
  bool frame_dropped = false;
  int features_prev = 0, features_curr = 0;
  int matches = 0;      // symmetric ratio-test matches
  bool rematched = false;  // the windowed search fell short; matched again over the whole image
  int point_pairs = 0;  // matches with usable depth in both frames
  int tracked = 0;      // of those, the ones whose current keypoint the sub-pixel tracker moved
  int inliers = 0;
  double inlier_threshold_m = 0;
  int depth_points = 0;  // depth points of the alignment fused with the features; 0: features alone
  bool depth_trusted = false;  // fused at the learnt trust, not at refinement.distrusted_sigma_scale
  SensorEstimates sensor;  // the sensor's constants as learnt up to this pair
  CaptureTiming timing;    // t_prev_ns, t_curr_ns restamped at the capture instants, when a gyro is read
  // The depth maps' own rotation (their alignment's, before any fusion) over the depth frames'
  // interval, stamped on the pair's timeline before any restamping: the depth stream's latency
  // is measured against the gyro with it. NaN where the depths were not aligned.
  Eigen::Vector3d depth_rotation = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  std::int64_t t_depth_prev_ns = 0, t_depth_curr_ns = 0;
  Eigen::Isometry3d T_prev_curr = Eigen::Isometry3d::Identity();  // curr camera pose in prev camera frame
  // The newer frame's depth-instant shift (pipeline/depth_clock.hpp: along its optical axis, and
  // its tilt along the slide): the keyframes carry their measurements of it to the colour's
  // instants as the pair was.
  Eigen::Isometry3d depth_shift = Eigen::Isometry3d::Identity();
  KeyframeLink keyframe;
  Matrix6d covariance = Matrix6d::Constant(std::numeric_limits<double>::quiet_NaN());  // of xi = (t, rotvec)
  // The same before the capture latencies' terms: the error of the motion between the two
  // capture instants, what the keyframes weigh the pair by (pipeline/keyframes.hpp).
  Matrix6d motion_covariance = Matrix6d::Constant(std::numeric_limits<double>::quiet_NaN());
  StageTimes times;
};

}  // namespace rgbdo
