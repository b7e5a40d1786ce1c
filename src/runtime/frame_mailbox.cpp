#include "rgbd_odometry/runtime/frame_mailbox.hpp"

#include <utility>

namespace rgbdo {

bool FrameMailbox::publish() {
  std::unique_lock<std::mutex> lock(mutex_);
  if (lossless_) changed_.wait(lock, [&] { return !has_waiting_ || closed_; });
  if (closed_) return false;
  if (has_waiting_) {
    // Processing is behind: the waiting frame is dropped for the newer one, whose pair will
    // span both intervals (its dt is measured from the last frame processed).
    CapturedFrame& replaced = slots_[waiting_];
    CapturedFrame& newer = slots_[fill_];
    newer.skipped_before += replaced.skipped_before + 1;
    newer.after_gap = newer.after_gap || replaced.after_gap;
    ++skipped_;
  }
  std::swap(fill_, waiting_);
  has_waiting_ = true;
  changed_.notify_all();
  return true;
}

CapturedFrame* FrameMailbox::take() {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [&] { return has_waiting_ || closed_; });
  if (!has_waiting_) return nullptr;
  std::swap(taken_, waiting_);
  has_waiting_ = false;
  changed_.notify_all();
  return &slots_[taken_];
}

void FrameMailbox::close() {
  std::lock_guard<std::mutex> lock(mutex_);
  closed_ = true;
  changed_.notify_all();
}

std::uint64_t FrameMailbox::skipped() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return skipped_;
}

}  // namespace rgbdo
