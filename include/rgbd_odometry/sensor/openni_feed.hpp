#pragma once
// An OpenNI2 device as a frame feed: a live sensor, the virtual sensor, or an .oni recording
// played by OpenNI2's file driver. Lost when the device stops delivering; reopen() opens it
// afresh (sensor/reconnecting_feed.hpp decides when).
#include <atomic>
#include <memory>
#include <mutex>
#include <string>

#include "rgbd_odometry/io/frame_feed.hpp"
#include "rgbd_odometry/sensor/sensor_openni.hpp"

namespace rgbdo {

class OpenNiFeed : public FrameFeed {
 public:
  // Opens the device now (throws SourceError when it cannot). A path ending in .oni plays that
  // recording through OpenNI2's file driver, once, every frame (not live: nothing skipped).
  OpenNiFeed(const OpenNiOptions& options, int max_frames);
  FeedState next(RgbdFrame& frame, std::string& problem) override;
  bool live() const override { return !playback_; }
  // One attempt to open the device again after Lost; false (with `problem`) when not back yet.
  // The policy of when to try is ReconnectingFeed's.
  bool reopen(std::string& problem);
  void interrupt() override;
  std::string description() const override;
  int dropped_frames() const override;
  int frames_without_depth() const override;

 private:
  OpenNiOptions options_;
  int max_frames_, delivered_ = 0, opens_ = 1, dropped_before_ = 0, without_depth_before_ = 0;
  bool playback_;
  mutable std::mutex mutex_;  // guards source_ against interrupt() from another thread
  std::unique_ptr<OpenNiSource> source_;
  std::atomic<bool> interrupted_{false};
};

}  // namespace rgbdo
