#include "rgbd_odometry/io/tum_feed.hpp"

#include <algorithm>

namespace rgbdo {

TumFeed::TumFeed(TumSequence sequence, const PipelineConfig& config, int max_frames)
    : seq_(std::move(sequence)), config_(config),
      end_(max_frames > 0 ? std::min(seq_.frames.size(), static_cast<size_t>(max_frames)) : seq_.frames.size()) {}

FeedState TumFeed::next(RgbdFrame& frame, std::string& problem) {
  if (interrupted_) {
    problem = "interrupted";
    return FeedState::End;
  }
  if (i_ >= end_) return FeedState::End;
  frame = load_tum_frame(seq_.frames[i_++], config_.depth.units_per_m, config_.camera.width, config_.camera.height);
  return FeedState::Frame;
}

std::string TumFeed::description() const {
  return "TUM RGB-D sequence " + seq_.directory + " (" + std::to_string(end_) + " frames)";
}

}  // namespace rgbdo
