#include "rgbd_odometry/pipeline/odometry.hpp"

#include <chrono>
#include <utility>

#include "rgbd_odometry/core/clock.hpp"

namespace rgbdo {

OdometryPipeline::OdometryPipeline(const PipelineConfig& config)
    : extractor_(config),
      estimator_(config),
      keyframes_(config),
      reported_(config.covariance) {}

std::optional<PairResult> OdometryPipeline::process(const RgbdFrame& frame) {
  const auto start = std::chrono::steady_clock::now();
  extractor_.extract(frame, curr_);
  const double detect_ms = ms_since(start);
  std::optional<PairResult> result;
  if (have_prev_) {
    result = estimator_.estimate(prev_, curr_);
    result->times.detect_ms = detect_ms;
    if (PairEstimator::dropped_frame(*result)) return result;  // prev_ stays the previous frame
    keyframes_.update(curr_, *result);
    reported_.report(*result);
  }
  std::swap(prev_, curr_);  // swap, not copy: buffers are reused frame after frame
  have_prev_ = true;
  return result;
}

}  // namespace rgbdo
