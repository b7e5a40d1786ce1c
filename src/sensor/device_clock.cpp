#include "rgbd_odometry/sensor/device_clock.hpp"

#include <cmath>

namespace rgbdo {

std::int64_t DeviceClock::to_host(std::int64_t device_ns, std::int64_t arrival_host_ns) {
  const std::int64_t offset = arrival_host_ns - device_ns;  // delay + clock offset
  if (!started_) {
    started_ = true;
    anchor_device_ns_ = origin_device_ns_ = window_start_ns_ = window_min_at_ns_ = device_ns;
    anchor_host_ns_ = arrival_host_ns;
    origin_offset_ns_ = window_min_ns_ = offset;
    return arrival_host_ns;
  }
  // The host time on the current rate, before this frame's own arrival can change it: the
  // frame is mapped exactly as its predecessors were.
  const auto mapped = [&] {
    return anchor_host_ns_ +
           static_cast<std::int64_t>(std::llround(static_cast<double>(device_ns - anchor_device_ns_) * (1.0 + skew_)));
  };
  if (!follow_rate_) return mapped();
  // A frame cannot be captured after it arrived. When the mapping says otherwise, the anchor's
  // transport delay was longer than this frame's (the first frame's often is: start-up), and
  // the mapping moves down to this arrival: one backward step, at most the excess delay.
  // Not for a clock that runs at another speed on purpose (seen over a second or more of
  // device time, or by the fit): its times run ahead of any arrival by design.
  const auto at_most_arrival = [&](std::int64_t host_ns) {
    if (host_ns <= arrival_host_ns || implausible_) return host_ns;
    const std::int64_t baseline_ns = device_ns - origin_device_ns_;
    if (baseline_ns >= kOtherSpeedBaselineNs &&
        std::fabs(static_cast<double>(offset - origin_offset_ns_) / static_cast<double>(baseline_ns)) > kOtherSpeed)
      return host_ns;
    anchor_device_ns_ = device_ns;
    anchor_host_ns_ = arrival_host_ns;
    ++lowered_;
    return arrival_host_ns;
  };
  if (device_ns - window_start_ns_ < kWindowNs) {
    if (offset < window_min_ns_) {
      window_min_ns_ = offset;
      window_min_at_ns_ = device_ns;
    }
    return at_most_arrival(mapped());
  }
  // A window closed: its minimum joins the fit (in seconds and microseconds, well conditioned).
  const double t = static_cast<double>(window_min_at_ns_ - origin_device_ns_) * 1e-9;
  const double m = static_cast<double>(window_min_ns_ - origin_offset_ns_) * 1e-3;
  n_ = kForget * n_ + 1;
  sum_t_ = kForget * sum_t_ + t;
  sum_m_ = kForget * sum_m_ + m;
  sum_tt_ = kForget * sum_tt_ + t * t;
  sum_tm_ = kForget * sum_tm_ + t * m;
  window_start_ns_ = window_min_at_ns_ = device_ns;
  window_min_ns_ = offset;
  const double spread = sum_tt_ - sum_t_ * sum_t_ / n_;
  if (++windows_ >= 2 && spread > 0) {
    const double slope = (sum_tm_ - sum_t_ * sum_m_ / n_) / spread * 1e-6;  // host s per device s, minus 1
    implausible_ = std::fabs(slope) > kMaxSkew;
    if (!implausible_) {
      const std::int64_t now = mapped();  // continuous: the new rate starts where the old one is
      anchor_device_ns_ = device_ns;
      anchor_host_ns_ = now;
      skew_ = slope;
    }
  }
  return at_most_arrival(mapped());
}

}  // namespace rgbdo
