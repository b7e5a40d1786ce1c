#include "rgbd_odometry/pipeline/frame_extractor.hpp"

#include <opencv2/core.hpp>

#include "rgbd_odometry/core/cost_stage.hpp"
#include "rgbd_odometry/pipeline/mask.hpp"
#include "rgbd_odometry/pipeline/track.hpp"

namespace rgbdo {

FrameExtractor::FrameExtractor(const PipelineConfig& config, TaskRunner* runner)
    : depth_(config.depth),
      width_(config.camera.width),
      height_(config.camera.height),
      border_px_(config.features.border_px),
      min_features_(config.ransac.min_inliers),
      detector_(config.features, runner),
      backprojector_(config.camera, config.depth),
      keep_gray_(tracks_keypoints(config)) {
  // The paper's model never refines (pair_estimator.cpp): no clouds to build for it.
  if (config.refinement.enabled && config.covariance.model != "paper") cloud_builder_.emplace(config.camera, config.depth, config.refinement);
}

void FrameExtractor::extract(const RgbdFrame& frame, ProcessedFrame& out) {
  out.times = {frame.t_colour_ns, frame.t_depth_ns, frame.host_lead_ns};
  out.status = frame.status;
  out.problem = frame.problem;  // empty for good frames: no allocation
  out.features.keypoints.clear();
  out.geometry.clear();
  out.cloud.cols = out.cloud.rows = 0;  // keeps its buffers
  if (frame.status != Status::Ok) return;
  // Of the camera's size only: the intrinsics are for it, and the depth cloud samples the depth
  // image at pixels laid out for it (a smaller image was read past its end: fuzz_images).
  if (frame.gray.type() != CV_8UC1 || frame.depth_m.type() != CV_32FC1 || frame.gray.cols != width_ ||
      frame.gray.rows != height_ || frame.depth_m.size() != frame.gray.size()) {
    out.status = Status::BadFrame;
    out.problem = "a frame the pipeline cannot take: intensity " + cv::typeToString(frame.gray.type()) + " " +
                  std::to_string(frame.gray.cols) + "x" + std::to_string(frame.gray.rows) + ", depth " +
                  cv::typeToString(frame.depth_m.type()) + " " + std::to_string(frame.depth_m.cols) + "x" +
                  std::to_string(frame.depth_m.rows) + " (needs 8UC1 and 32FC1 of the camera's " +
                  std::to_string(width_) + "x" + std::to_string(height_) + ")";
    return;
  }
  const CostStagesEnd stages_end;
  mark_cost_stage(CostStage::Mask);
  build_feature_mask(frame.depth_m, depth_, border_px_, mask_);
  if (mask_is_empty(mask_)) {
    out.status = Status::NoDepth;
    return;
  }
  mark_cost_stage(CostStage::Detect);
  detector_.detect(frame.gray, mask_, out.features);
  mark_cost_stage(CostStage::Geometry);
  backprojector_.compute(out.features.keypoints, frame.depth_m, out.geometry);
  if (keep_gray_) frame.gray.copyTo(out.gray);  // the pair's tracker reads it; reuses out's buffer
  if (cloud_builder_) {
    mark_cost_stage(CostStage::Refine);
    cloud_builder_->build(frame.depth_m, out.cloud);
  }
  if (static_cast<int>(out.features.keypoints.size()) < min_features_) out.status = Status::TooFewFeatures;
}

}  // namespace rgbdo
