#pragma once
// The fixed pipeline on one thread: feed RGB-D frames in capture order, get one result per
// consecutive pair. Stages: mask -> detect -> back-project (FrameExtractor, per frame), then
// match -> point pairs -> RANSAC -> covariance (PairEstimator, per pair), then the keyframe's
// measurement (KeyframeTracker) and the covariance that goes out (ReportedCovariance). The
// real-time runtime (runtime/realtime.hpp) runs the two halves on their own threads instead.
#include <cstdint>
#include <optional>

#include "rgbd_odometry/pipeline/pipeline_config.hpp"
#include "rgbd_odometry/core/pair_result.hpp"
#include "rgbd_odometry/pipeline/frame.hpp"
#include "rgbd_odometry/pipeline/frame_extractor.hpp"
#include "rgbd_odometry/pipeline/keyframes.hpp"
#include "rgbd_odometry/pipeline/pair_estimator.hpp"
#include "rgbd_odometry/pipeline/reported_covariance.hpp"

namespace rgbdo {

class OdometryPipeline {
 public:
  explicit OdometryPipeline(const PipelineConfig& config);  // config must have passed validate()

  // The first frame returns nothing; each later one returns the (previous, this) pair.
  [[nodiscard]] std::optional<PairResult> process(const RgbdFrame& frame);

 private:
  FrameExtractor extractor_;
  PairEstimator estimator_;
  KeyframeTracker keyframes_;
  ReportedCovariance reported_;
  ProcessedFrame prev_, curr_;
  bool have_prev_ = false;
};

}  // namespace rgbdo
