#pragma once
// The "most recent problem" of a link, shared by the UDP and serial transports (private to
// src/). A peer that refuses every datagram at 30 Hz must cost the output thread no string
// formatting, no allocation and no wait: report() only stores a literal and an errno; the text
// is composed when someone asks for it.
#include <cstdint>
#include <cstring>
#include <mutex>
#include <string>
#include <utility>

#include "rgbd_odometry/core/clock.hpp"

namespace rgbdo::link_detail {

// strerror_r is the XSI (int) or the GNU (char*) variant depending on the C library.
inline const char* strerror_result(int result, const char* buffer) { return result == 0 ? buffer : "unknown error"; }
inline const char* strerror_result(const char* result, const char*) { return result; }

inline std::string errno_text(int err) {
  char buffer[128] = {};
  return strerror_result(strerror_r(err, buffer, sizeof buffer), buffer);
}

class LinkProblem {
 public:
  explicit LinkProblem(std::string prefix) : prefix_(std::move(prefix)) {}

  // `what` must be a string literal (it is kept by pointer); err is an errno value or 0.
  // From the output thread pass may_wait = false: if a reader holds the lock this occurrence
  // is not recorded (the caller's own counters still are), rather than waiting for it.
  void report(const char* what, int err, bool may_wait = true) noexcept {
    std::unique_lock lock(mutex_, std::defer_lock);
    if (may_wait)
      lock.lock();
    else if (!lock.try_lock())
      return;
    const std::int64_t now_ns = steady_now_ns();
    const bool same = what == what_ && err == err_;
    repeats_ = same ? repeats_ + 1 : 1;
    // Once a second while the same problem persists, so a logger keyed on the count writes
    // one line a second, not thirty.
    if (!same || now_ns - last_report_ns_ >= kRepeatReportInterval_ns) {
      ++reports_;
      last_report_ns_ = now_ns;
    }
    what_ = what;
    err_ = err;
  }

  std::string text() const {
    std::lock_guard lock(mutex_);
    if (what_ == nullptr) return {};
    std::string s = prefix_ + ": " + what_;
    if (err_ != 0) s += ": " + errno_text(err_);
    if (repeats_ > 1) s += " (" + std::to_string(repeats_) + " times)";
    return s;
  }

  std::uint64_t reports() const {
    std::lock_guard lock(mutex_);
    return reports_;
  }

 private:
  static constexpr std::int64_t kRepeatReportInterval_ns = 1'000'000'000;
  const std::string prefix_;
  mutable std::mutex mutex_;
  const char* what_ = nullptr;
  int err_ = 0;
  std::uint64_t repeats_ = 0;  // consecutive occurrences of the current problem
  std::uint64_t reports_ = 0;
  std::int64_t last_report_ns_ = 0;
};

}  // namespace rgbdo::link_detail
