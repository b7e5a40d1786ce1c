#pragma once
// Where frames come from, behind one interface: a recorded TUM sequence (io/tum_feed.hpp, read
// as fast as the pipeline takes it, nothing skipped) or an OpenNI2 device (sensor/, a live
// sensor, the virtual sensor or an .oni recording), which may be lost and come back. The
// runtime reads frames through it and knows no sensor.
#include <atomic>
#include <cstdint>
#include <optional>
#include <string>

#include "rgbd_odometry/io/tum_sequence.hpp"
#include "rgbd_odometry/pipeline/frame.hpp"

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
  // After Lost: waits for the source to come back (true: next() delivers again) or gives up
  // (false: past the source's own timeout, with `problem` saying why, or as soon as
  // `stopping` holds). A source that cannot come back returns false at once.
  virtual bool wait_for_return(const std::atomic<bool>& /*stopping*/, std::string& /*problem*/) { return false; }
  // What the source has to tell since the last call (a device leaving the bus...), or empty.
  // Called from one thread (the runtime's output thread).
  virtual std::string news() { return {}; }
  // Makes a blocking next() return promptly (End); thread-safe, for shutdown.
  virtual void interrupt() = 0;
  virtual const GroundTruth* groundtruth() const { return nullptr; }
  virtual std::string description() const = 0;
  virtual int dropped_frames() const { return 0; }  // by the sensor, seen from frame indices
  // Live colour frames given up because no depth frame came within 20 ms of them before newer
  // colour frames did (a sensor or recording that lost depth frames): counted apart from the
  // frames the processing threads could not take. Thread-safe, as dropped_frames().
  virtual int frames_without_depth() const { return 0; }
  // A recording's folder, where its imu.txt would be; empty for a live source.
  virtual std::string recording_directory() const { return {}; }
  // The first frame's colour stamp where it is known before reading (a recording).
  virtual std::optional<std::int64_t> first_frame_stamp_ns() const { return std::nullopt; }
};

}  // namespace rgbdo
