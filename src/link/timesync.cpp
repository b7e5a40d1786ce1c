#include "rgbd_odometry/link/timesync.hpp"

#include <algorithm>

namespace rgbdo {

void TimesyncEstimator::note_request(std::int64_t ts1_ns) {
  outstanding_[next_outstanding_] = ts1_ns;  // the oldest request gives way
  next_outstanding_ = (next_outstanding_ + 1) % kOutstanding;
}

TimesyncEstimator::Answer TimesyncEstimator::add_answer(std::int64_t tc1_ns, std::int64_t ts1_ns, std::int64_t now_ns) {
  const auto ours = std::find(outstanding_.begin(), outstanding_.end(), ts1_ns);
  if (ts1_ns == 0 || ours == outstanding_.end()) {
    ++rejected_;
    return Answer::NotOurs;
  }
  *ours = 0;  // one answer per request: a duplicate is not a second sample
  const std::int64_t rtt_ns = now_ns - ts1_ns;
  if (rtt_ns < 0 || rtt_ns > max_rtt_ns_) {
    ++rejected_;
    return Answer::TooSlow;
  }
  // ts1 + rtt/2 without overflowing: our clock is nanoseconds since boot. tc1 comes off the
  // wire as any 64-bit value; one whose offset from our clock does not fit 64 bits (a negative
  // tc1 near -2^63: a broken or hostile peer) is no clock reading.
  std::int64_t offset_ns = 0;
  if (__builtin_sub_overflow(tc1_ns, ts1_ns + rtt_ns / 2, &offset_ns)) {
    ++rejected_;
    return Answer::ClockOutOfRange;
  }
  window_[next_sample_] = {offset_ns, rtt_ns};
  next_sample_ = (next_sample_ + 1) % kWindow;
  window_size_ = std::min(window_size_ + 1, kWindow);
  ++samples_;
  return Answer::Used;
}

TimesyncEstimate TimesyncEstimator::estimate() const {
  TimesyncEstimate e;
  e.samples = samples_;
  e.rejected = rejected_;
  if (window_size_ == 0) return e;
  const auto best = std::min_element(window_.begin(), window_.begin() + static_cast<std::ptrdiff_t>(window_size_),
                                     [](const Sample& a, const Sample& b) { return a.rtt_ns < b.rtt_ns; });
  e.valid = true;
  e.offset_ns = best->offset_ns;
  e.rtt_ns = best->rtt_ns;
  return e;
}

std::optional<std::int64_t> TimesyncEstimator::to_autopilot_ns(std::int64_t time_ns) const {
  const TimesyncEstimate e = estimate();
  std::int64_t autopilot_ns = 0;
  // An autopilot clock near 2^63 (tc1 is taken as it comes) can put the sum past 64 bits.
  if (!e.valid || __builtin_add_overflow(time_ns, e.offset_ns, &autopilot_ns)) return std::nullopt;
  return autopilot_ns;
}

void TimesyncEstimator::reset() {
  outstanding_.fill(0);
  window_size_ = next_sample_ = 0;
  samples_ = rejected_ = 0;
}

}  // namespace rgbdo
