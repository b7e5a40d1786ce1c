#pragma once
// The followed autopilot's angular rate, from its ATTITUDE messages (rollspeed, pitchspeed,
// yawspeed: body FRD, rad/s), mapped onto our clock through the TIMESYNC offset and handed to
// the odometry's latency estimate (pipeline/capture_latency.hpp). The receiver thread adds;
// the estimation thread takes. A fixed ring: nothing is allocated after construction, and a
// reader that falls behind loses the oldest samples, counted.
//
// The stamps are the autopilot's: PX4's ATTITUDE carries the attitude's publication time and
// its low-pass-filtered rates; ArduPilot's the time it is sent. Both are a few milliseconds
// after the gyro sampled, which the latency measured against them leaves out.
#include <array>
#include <cstdint>
#include <mutex>
#include <optional>

#include "rgbd_odometry/core/gyro.hpp"

namespace rgbdo {

class AutopilotGyro : public GyroFeed {
 public:
  // An ATTITUDE's rates, stamped time_boot_ms on the autopilot's clock; offset_ns: autopilot
  // clock minus ours (TIMESYNC), nullopt while unknown (the sample is not usable, counted).
  void add(std::uint32_t time_boot_ms, float rollspeed, float pitchspeed, float yawspeed,
           std::optional<std::int64_t> offset_ns);
  // Another autopilot, or the same one rebooted: its stamps are on another clock.
  void clear();

  std::size_t take(std::int64_t until_ns, std::span<GyroSample> out) override;
  std::string description() const override;

  struct Counts {
    std::uint64_t received = 0;  // ATTITUDE messages with finite rates
    std::uint64_t unmapped = 0;  // before the clock offset was known
    std::uint64_t overwritten = 0;  // not taken in time
  };
  Counts counts() const;

 private:
  static constexpr std::size_t kSamples = 1024;  // 5 s at 200 Hz
  mutable std::mutex mutex_;
  std::array<GyroSample, kSamples> ring_{};
  std::size_t first_ = 0, count_ = 0;
  Counts counts_;
};

}  // namespace rgbdo
