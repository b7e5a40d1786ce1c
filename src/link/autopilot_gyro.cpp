#include "rgbd_odometry/link/autopilot_gyro.hpp"

#include <cmath>
#include <sstream>

namespace rgbdo {

void AutopilotGyro::add(std::uint32_t time_boot_ms, float rollspeed, float pitchspeed, float yawspeed,
                        std::optional<std::int64_t> offset_ns) {
  if (!std::isfinite(rollspeed) || !std::isfinite(pitchspeed) || !std::isfinite(yawspeed)) return;
  std::lock_guard lock(mutex_);
  ++counts_.received;
  if (!offset_ns) {
    ++counts_.unmapped;
    return;
  }
  const GyroSample s{static_cast<std::int64_t>(time_boot_ms) * 1'000'000 - *offset_ns,
                     Eigen::Vector3d(rollspeed, pitchspeed, yawspeed)};
  if (count_ == kSamples) {
    first_ = (first_ + 1) % kSamples;
    --count_;
    ++counts_.overwritten;
  }
  ring_[(first_ + count_) % kSamples] = s;
  ++count_;
}

void AutopilotGyro::clear() {
  std::lock_guard lock(mutex_);
  first_ = count_ = 0;
}

std::size_t AutopilotGyro::take(std::int64_t /*until_ns: live, what has arrived*/, std::span<GyroSample> out) {
  std::lock_guard lock(mutex_);
  std::size_t n = 0;
  while (n < out.size() && count_ > 0) {
    out[n++] = ring_[first_];
    first_ = (first_ + 1) % kSamples;
    --count_;
  }
  return n;
}

std::string AutopilotGyro::description() const { return "the autopilot's ATTITUDE rates (mapped through TIMESYNC)"; }

AutopilotGyro::Counts AutopilotGyro::counts() const {
  std::lock_guard lock(mutex_);
  return counts_;
}

}  // namespace rgbdo
