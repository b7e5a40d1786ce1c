#pragma once
// The fixed pipeline: feed RGB-D frames in capture order, get one result per consecutive
// pair. Stages: mask -> detect -> match -> back-project -> RANSAC -> covariance.
#include <Eigen/Geometry>
#include <cstdint>
#include <optional>

#include "rgbd_odometry/backproject.hpp"
#include "rgbd_odometry/config.hpp"
#include "rgbd_odometry/covariance.hpp"
#include "rgbd_odometry/detect.hpp"
#include "rgbd_odometry/frame.hpp"
#include "rgbd_odometry/geometry.hpp"
#include "rgbd_odometry/match.hpp"
#include "rgbd_odometry/ransac.hpp"
#include "rgbd_odometry/status.hpp"

namespace rgbdo {

struct StageTimes {  // wall time of each stage for this pair, milliseconds
  double detect_ms = 0;       // mask + detection + description + keypoint geometry, current frame
  double match_ms = 0;
  double backproject_ms = 0;  // building the 3-D pairs (incl. the timing-compensation pass)
  double ransac_ms = 0;
  double covariance_ms = 0;
};

struct PairResult {
  std::int64_t t_prev_ns = 0;  // colour capture times of the two frames
  std::int64_t t_curr_ns = 0;
  Status status = Status::Ok;
  int features_prev = 0, features_curr = 0;
  int matches = 0;      // symmetric ratio-test matches
  int point_pairs = 0;  // matches with usable depth in both frames
  int inliers = 0;
  double inlier_threshold_m = 0;
  Eigen::Isometry3d T_prev_curr = Eigen::Isometry3d::Identity();  // curr camera pose in prev camera frame
  Matrix6d covariance = Matrix6d::Constant(std::numeric_limits<double>::quiet_NaN());  // of xi = (t, rotvec)
  StageTimes times;
};

// Everything the pipeline keeps of one frame.
struct ProcessedFrame {
  FrameTimes times;
  Status status = Status::Ok;
  std::string problem;  // the source's words for a failed frame (names the file, say)
  Features features;
  KeypointGeometry geometry;
};

class OdometryPipeline {
 public:
  explicit OdometryPipeline(const Config& config);  // config must have passed validate()

  // The first frame returns nothing; each later one returns the (previous, this) pair.
  [[nodiscard]] std::optional<PairResult> process(const RgbdFrame& frame);

  // The pair stage alone, on frames already through extract() (benchmarks, tests).
  void extract(const RgbdFrame& frame, ProcessedFrame& out);
  [[nodiscard]] PairResult estimate(const ProcessedFrame& prev, const ProcessedFrame& curr, std::uint64_t pair_index);

  // A gap in the frames (sensor lost): the last pair's velocity no longer predicts the next.
  void forget_motion() { last_motion_.reset(); }

  const Config& config() const { return config_; }

 private:
  Config config_;
  FeatureDetector detector_;
  SymmetricMatcher matcher_;
  KeypointBackProjector backprojector_;
  RigidRansac ransac_;
  PerturbationCovariance covariance_;
  cv::Mat mask_;
  std::vector<Match> matches_;
  PointPairs pairs_;
  RansacResult fit_, refined_;
  std::vector<Eigen::Vector3d> inlier_prev_, inlier_curr_;
  ProcessedFrame prev_, curr_;
  bool have_prev_ = false;
  std::uint64_t pair_index_ = 0;
  double last_detect_ms_ = 0;
  // Velocity of the last good pair: the motion prior for timing compensation.
  std::optional<MotionPrior> last_motion_;
};

}  // namespace rgbdo
