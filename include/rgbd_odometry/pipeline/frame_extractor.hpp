#pragma once
// The per-frame half of the pipeline: mask -> detect + describe -> keypoint geometry. Its
// state (detector, mask and back-projection buffers) lives as long as the frame stream and
// is touched by one thread; each frame's result is a ProcessedFrame that the per-pair half
// (pair_estimator.hpp) reads twice, as the newer and then as the older frame of a pair.
#include <optional>
#include <string>

#include "rgbd_odometry/pipeline/pipeline_config.hpp"
#include "rgbd_odometry/core/status.hpp"
#include "rgbd_odometry/pipeline/backproject.hpp"
#include "rgbd_odometry/pipeline/depth_alignment.hpp"
#include "rgbd_odometry/pipeline/detect.hpp"
#include "rgbd_odometry/pipeline/frame.hpp"

namespace rgbdo {

// Everything the pipeline keeps of one frame.
struct ProcessedFrame {
  FrameTimes times;
  Status status = Status::Ok;
  std::string problem;  // the source's words for a failed frame (names the file, say)
  Features features;
  KeypointGeometry geometry;
  DepthCloud cloud;  // empty when refinement.enabled is off
  cv::Mat gray;      // the intensity image, for the sub-pixel tracker (empty when it is off)
};

class FrameExtractor {
 public:
  // config must have passed validate(); runner: where detection may split its work (null:
  // all on the calling thread; the result is the same).
  explicit FrameExtractor(const PipelineConfig& config, TaskRunner* runner = nullptr);

  // Overwrites `out`, reusing its buffers. A failed frame keeps its status and problem.
  void extract(const RgbdFrame& frame, ProcessedFrame& out);

 private:
  DepthConfig depth_;
  int width_, height_;  // the camera's: the intrinsics and the depth clouds' sampling are for it
  int border_px_;
  int min_features_;  // fewer than a pose needs: the frame is flagged TooFewFeatures
  FeatureDetector detector_;
  KeypointBackProjector backprojector_;
  std::optional<DepthCloudBuilder> cloud_builder_;
  bool keep_gray_;  // tracks_keypoints(config): the pair's tracker reads the intensity image
  cv::Mat mask_;
};

}  // namespace rgbdo
