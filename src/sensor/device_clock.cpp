#include "rgbd_odometry/sensor/device_clock.hpp"

#include <algorithm>
#include <cmath>

namespace rgbdo {

std::int64_t DeviceClock::to_host(std::int64_t device_ns, std::int64_t arrival_host_ns) {
  const std::int64_t timeline_ns = map(device_ns, arrival_host_ns);
  lead_ns_ = std::max(lead_ns_, timeline_ns - arrival_host_ns);
  return timeline_ns;
}

std::int64_t DeviceClock::map(std::int64_t device_ns, std::int64_t arrival_host_ns) {
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
  if (device_ns - window_start_ns_ < kWindowNs) {
    if (offset < window_min_ns_) {
      window_min_ns_ = offset;
      window_min_at_ns_ = device_ns;
    }
    return mapped();
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
  return mapped();
}

}  // namespace rgbdo
