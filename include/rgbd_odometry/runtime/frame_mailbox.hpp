#pragma once
// The hand-over from the capture thread to processing: three frame buffers, allocated once
// and reused (one being filled, one waiting, one being processed). A live source must never
// wait, so a newer frame replaces a waiting one the processing has not taken yet: the newest
// frame wins and the replaced ones are counted. A recorded source waits instead: nothing lost.
#include <array>
#include <condition_variable>
#include <cstdint>
#include <mutex>

#include "rgbd_odometry/pipeline/frame.hpp"

namespace rgbdo {

struct CapturedFrame {
  RgbdFrame frame;
  std::int64_t t_capture_host_ns = 0;  // steady clock: when the sensor captured it (live) or it was read
  int skipped_before = 0;              // frames replaced before this one was taken
  bool after_gap = false;              // first frame after the sensor was lost and re-opened
};

class FrameMailbox {
 public:
  explicit FrameMailbox(bool lossless) : lossless_(lossless) {}

  // Capture thread: the buffer to fill next (valid until publish()).
  CapturedFrame& fill_slot() { return slots_[fill_]; }
  // Capture thread: hands the filled buffer over. Never waits when live; when lossless,
  // waits until the previous frame was taken. False when the mailbox was closed.
  bool publish();
  // Processing: waits for the next frame; nullptr once closed and empty. The frame stays
  // valid until the next take().
  CapturedFrame* take();
  void close();
  std::uint64_t skipped() const;

 private:
  const bool lossless_;
  std::array<CapturedFrame, 3> slots_;
  int fill_ = 0, waiting_ = 1, taken_ = 2;
  bool has_waiting_ = false, closed_ = false;
  std::uint64_t skipped_ = 0;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
};

}  // namespace rgbdo
