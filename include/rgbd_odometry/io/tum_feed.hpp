#pragma once
// A recorded TUM RGB-D sequence as a frame feed: every frame, in order, as fast as the pipeline
// takes it.
#include <atomic>
#include <cstdint>
#include <optional>
#include <string>

#include "rgbd_odometry/pipeline/pipeline_config.hpp"
#include "rgbd_odometry/io/frame_feed.hpp"
#include "rgbd_odometry/io/tum_sequence.hpp"

namespace rgbdo {

class TumFeed : public FrameFeed {
 public:
  TumFeed(TumSequence sequence, const PipelineConfig& config, int max_frames);
  FeedState next(RgbdFrame& frame, std::string& problem) override;
  bool live() const override { return false; }
  void interrupt() override { interrupted_ = true; }
  const GroundTruth* groundtruth() const override { return &seq_.groundtruth; }
  std::string description() const override;
  const TumSequence& sequence() const { return seq_; }
  std::string recording_directory() const override { return seq_.directory; }
  std::optional<std::int64_t> first_frame_stamp_ns() const override {
    if (seq_.frames.empty()) return std::nullopt;
    return seq_.frames.front().t_colour_ns;
  }

 private:
  TumSequence seq_;
  PipelineConfig config_;
  size_t end_, i_ = 0;
  std::atomic<bool> interrupted_{false};
};

}  // namespace rgbdo
