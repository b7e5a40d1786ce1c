#pragma once
// Where frames come from, behind one interface: a recorded TUM sequence (read as fast as the
// pipeline takes it, nothing skipped) or an OpenNI2 device (a live sensor, the virtual sensor
// or an .oni recording played by OpenNI2's file driver), which may be lost and come back.
#include <atomic>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>

#include "rgbd_odometry/core/config.hpp"
#include "rgbd_odometry/pipeline/frame.hpp"
#include "rgbd_odometry/sensor/sensor_openni.hpp"
#include "rgbd_odometry/io/tum_sequence.hpp"

namespace rgbdo {

enum class FeedState {
  Frame,  // a frame was delivered
  Lost,   // the sensor stopped delivering; reopen() may bring it back
  End,    // nothing more will come (end of a recording, or interrupted)
};

class FrameFeed {
 public:
  virtual ~FrameFeed() = default;
  // Fills `frame` (reusing its buffers where the source can). On Lost/End `problem` says why.
  virtual FeedState next(RgbdFrame& frame, std::string& problem) = 0;
  // Live sources run at the sensor's pace: a frame not taken in time is replaced by a newer
  // one. Recorded ones wait for the pipeline: nothing is skipped.
  virtual bool live() const = 0;
  // One attempt to open the source again after Lost; false (with `problem`) when not back yet.
  virtual bool reopen(std::string& /*problem*/) { return false; }
  // Makes a blocking next() return promptly (End); thread-safe, for shutdown.
  virtual void interrupt() = 0;
  virtual const GroundTruth* groundtruth() const { return nullptr; }
  virtual std::string description() const = 0;
  virtual int dropped_frames() const { return 0; }  // by the sensor, seen from frame indices
  // Live frames the reader replaced by a newer one before it could deliver them (it fell
  // behind, e.g. while waiting for a frame's depth): skipped, like frames the processing
  // threads could not take. Thread-safe, as dropped_frames().
  virtual int replaced_frames() const { return 0; }
};

class TumFeed : public FrameFeed {
 public:
  TumFeed(TumSequence sequence, const Config& config, int max_frames);
  FeedState next(RgbdFrame& frame, std::string& problem) override;
  bool live() const override { return false; }
  void interrupt() override { interrupted_ = true; }
  const GroundTruth* groundtruth() const override { return &seq_.groundtruth; }
  std::string description() const override;
  const TumSequence& sequence() const { return seq_; }

 private:
  TumSequence seq_;
  Config config_;
  size_t end_, i_ = 0;
  std::atomic<bool> interrupted_{false};
};

class OpenNiFeed : public FrameFeed {
 public:
  // Opens the device now (throws SourceError when it cannot). A path ending in .oni plays that
  // recording through OpenNI2's file driver, once, every frame (not live: nothing skipped).
  OpenNiFeed(const OpenNiOptions& options, int max_frames);
  FeedState next(RgbdFrame& frame, std::string& problem) override;
  bool live() const override { return !playback_; }
  bool reopen(std::string& problem) override;
  void interrupt() override;
  std::string description() const override;
  int dropped_frames() const override;
  int replaced_frames() const override;

 private:
  OpenNiOptions options_;
  int max_frames_, delivered_ = 0, opens_ = 1, dropped_before_ = 0, replaced_before_ = 0;
  bool playback_;
  mutable std::mutex mutex_;  // guards source_ against interrupt() from another thread
  std::unique_ptr<OpenNiSource> source_;
  std::atomic<bool> interrupted_{false};
};

// A --source text that names no source this program reads (a usage error, not a failure to open).
class SourceSpecError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// The feed a source text names:
//   tum:DIR                   a TUM RGB-D sequence directory (recorded: nothing skipped)
//   openni://[DEVICE-URI]     a live OpenNI2 device, the first one found when empty
//   oni:FILE.oni              an OpenNI2 recording played through OpenNI2's file driver
// Throws SourceSpecError for any other text, SourceError when the source cannot be opened.
std::unique_ptr<FrameFeed> open_frame_feed(const std::string& source, const Config& config, int max_frames);

}  // namespace rgbdo
