// Device-to-host clock mapping (src/sensor/device_clock.cpp) on simulated hour-long captures: a
// crystal off by tens of ppm, USB transport delays with a floor and a long tail, and a clock
// that runs at another speed on purpose (the virtual sensor at rate != 1).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "rgbd_odometry/sensor/device_clock.hpp"

namespace rgbdo {
namespace {

struct Capture {
  std::int64_t device_ns, true_host_ns, arrival_host_ns;
};

// `seconds` of 30 Hz frames. The device clock runs (1 + drift) device seconds per host second
// from an arbitrary start; each frame arrives 2 ms + an exponential tail (mean 1 ms) after it
// was captured, and one frame in a hundred waits 20 ms more (a busy reader).
std::vector<Capture> simulate(double seconds, double drift, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::exponential_distribution<double> tail(1.0 / 1e6);  // ns
  std::uniform_real_distribution<double> unit(0, 1);
  std::vector<Capture> out;
  const std::int64_t host0 = 5'000'000'000'000, device0 = 123'456'789'000;
  for (std::int64_t k = 0; k < static_cast<std::int64_t>(seconds * 30); ++k) {
    const std::int64_t host = host0 + k * 33'333'333;
    const auto device = device0 + static_cast<std::int64_t>(std::llround(static_cast<double>(host - host0) * (1 + drift)));
    auto delay = 2'000'000 + static_cast<std::int64_t>(tail(rng));
    if (unit(rng) < 0.01) delay += 20'000'000;
    out.push_back({device, host, host + delay});
  }
  return out;
}

// Host times of every frame, in order, as the source would map them.
std::vector<std::int64_t> map_all(DeviceClock& clock, const std::vector<Capture>& frames) {
  std::vector<std::int64_t> mapped;
  for (const auto& f : frames) mapped.push_back(clock.to_host(f.device_ns, f.arrival_host_ns));
  return mapped;
}

class DriftingCrystal : public ::testing::TestWithParam<double> {};

TEST_P(DriftingCrystal, CaptureTimesStayOnTheHostClockForAnHourWithIntervalsIntact) {
  const double drift = GetParam();
  const auto frames = simulate(3600, drift, 7);
  DeviceClock clock;
  const std::vector<std::int64_t> mapped = map_all(clock, frames);

  // The mapping keeps two constant biases: the first frame's transport delay, and the drift
  // of the first two windows (10 s), before the rate is known. Beyond them it must follow the
  // host clock, to 0.3 ms, for the whole hour.
  const std::int64_t bias = frames[0].arrival_host_ns - frames[0].true_host_ns;
  double worst_ms = 0;
  for (size_t i = 30 * 60; i < frames.size(); ++i)
    worst_ms = std::max(worst_ms, std::fabs(static_cast<double>(mapped[i] - frames[i].true_host_ns - bias)) * 1e-6);
  const double before_the_rate_is_known_ms = std::fabs(drift) * 2 * 5.0 * 1e3;
  EXPECT_LT(worst_ms, before_the_rate_is_known_ms + 0.3) << "drift " << drift;
  // The obvious alternative, one offset for ever, is off by the drift times an hour.
  const auto& last = frames.back();
  const double fixed_offset_error_ms =
      std::fabs(static_cast<double>((last.device_ns - frames[0].device_ns) - (last.true_host_ns - frames[0].true_host_ns))) * 1e-6;
  EXPECT_GT(fixed_offset_error_ms, 50 * worst_ms);

  // Intervals: the device's, changed by the skew only (ppm), never by a jump.
  for (size_t i = 1; i < frames.size(); ++i) {
    const double device_dt = static_cast<double>(frames[i].device_ns - frames[i - 1].device_ns);
    const double host_dt = static_cast<double>(mapped[i] - mapped[i - 1]);
    ASSERT_NEAR(host_dt, device_dt, device_dt * 2 * std::fabs(drift) + 2.0) << "frame " << i;
  }
  EXPECT_NEAR(clock.skew(), -drift / (1 + drift), 3e-6);
  EXPECT_FALSE(clock.implausible_skew());
}

INSTANTIATE_TEST_SUITE_P(PartsPerMillion, DriftingCrystal, ::testing::Values(50e-6, -30e-6, 100e-6));

TEST(DeviceClock, AnExactCrystalKeepsTheDeviceIntervals) {
  const auto frames = simulate(600, 0, 11);
  DeviceClock clock;
  const std::vector<std::int64_t> mapped = map_all(clock, frames);
  for (size_t i = 1; i < frames.size(); ++i) {
    const double device_dt = static_cast<double>(frames[i].device_ns - frames[i - 1].device_ns);
    EXPECT_NEAR(static_cast<double>(mapped[i] - mapped[i - 1]), device_dt, 100.0) << "frame " << i;  // 0.1 us of 33 ms
  }
  EXPECT_LT(std::fabs(clock.skew()), 2e-6);
}

TEST(DeviceClock, AClockRunningAtAnotherSpeedIsNotFollowedAndSaysSo) {
  // The virtual sensor at rate=2: recorded seconds pass twice as fast as host seconds.
  const auto frames = simulate(60, 1.0, 3);
  DeviceClock clock;
  const std::vector<std::int64_t> mapped = map_all(clock, frames);
  for (size_t i = 1; i < frames.size(); ++i)
    EXPECT_EQ(mapped[i] - mapped[i - 1], frames[i].device_ns - frames[i - 1].device_ns) << "frame " << i;
  EXPECT_TRUE(clock.implausible_skew());
  EXPECT_EQ(clock.skew(), 0.0);
}

TEST(DeviceClock, ARecordingIsNeverFollowed) {
  // Played back at a reader's pace that happens to be 500 ppm off the recording's: a crystal
  // could be that far off, but a recording's intervals must stay exactly the recorded ones.
  const auto frames = simulate(120, 500e-6, 5);
  DeviceClock clock(/*follow_rate=*/false);
  const std::vector<std::int64_t> mapped = map_all(clock, frames);
  for (size_t i = 1; i < frames.size(); ++i)
    EXPECT_EQ(mapped[i] - mapped[i - 1], frames[i].device_ns - frames[i - 1].device_ns) << "frame " << i;
  EXPECT_EQ(clock.skew(), 0.0);
  // The same capture, followed, does change the intervals: the test above can fail.
  DeviceClock following;
  map_all(following, frames);
  EXPECT_NEAR(following.skew(), -500e-6, 5e-6);
}

TEST(DeviceClock, TheFirstFrameIsMappedToItsArrival) {
  DeviceClock clock;
  EXPECT_EQ(clock.to_host(42'000, 7'000'000'000), 7'000'000'000);
  EXPECT_EQ(clock.to_host(42'000 + 33'000'000, 7'050'000'000), 7'033'000'000);  // device interval, not arrival
}

TEST(DeviceClock, AFirstFrameReadLateLeavesNoCaptureTimeAfterItsArrival) {
  // The reader began 180 ms after the sensor: the first frame is read that late, the next few
  // come out of the driver's queue in a burst, then frames arrive 2-3 ms after capture.
  auto frames = simulate(60, 0, 13);
  for (size_t k = 0; k < 6; ++k)
    frames[k].arrival_host_ns = std::max(frames[k].arrival_host_ns, frames[0].true_host_ns + 180'000'000 +
                                                                        static_cast<std::int64_t>(k) * 100'000);
  DeviceClock clock;
  std::vector<std::int64_t> timeline, lead;
  for (const auto& f : frames) {
    timeline.push_back(clock.to_host(f.device_ns, f.arrival_host_ns));
    lead.push_back(clock.lead_ns());
  }
  // The timeline anchored at the late first arrival runs ~180 ms ahead; the lead takes that off.
  EXPECT_NEAR(static_cast<double>(clock.lead_ns()), 178e6, 2e6);
  for (size_t i = 0; i < frames.size(); ++i) {
    const std::int64_t host_capture = timeline[i] - lead[i];
    EXPECT_LE(host_capture, frames[i].arrival_host_ns) << "frame " << i;
    if (i > 0) {
      EXPECT_GE(lead[i], lead[i - 1]);  // a step down of the stamps, never up
      // The intervals stay the device's (to the fitted skew's ppm), whatever the lead did in between.
      EXPECT_NEAR(static_cast<double>(timeline[i] - timeline[i - 1]),
                  static_cast<double>(frames[i].device_ns - frames[i - 1].device_ns), 100.0)
          << "frame " << i;
    }
    // Never before the capture plus the least transport delay (2 ms, to the skew fit's ns): the lead takes off only
    // what a frame proved. After the burst, within the least delay seen so far, which closes
    // in on those 2 ms as frames come.
    EXPECT_GE(host_capture - frames[i].true_host_ns, 2'000'000 - 1'000) << "frame " << i;
    const std::int64_t late_by = host_capture - frames[i].true_host_ns;
    if (i >= 10) {
      EXPECT_LT(late_by, 3'000'000) << "frame " << i;
    }
    if (i >= 300) {
      EXPECT_LT(late_by, 2'100'000) << "frame " << i;
    }
  }
  // Without the lead, nearly every frame after the first would be stamped after it arrived.
  int ahead = 0;
  for (size_t i = 0; i < frames.size(); ++i) ahead += timeline[i] > frames[i].arrival_host_ns ? 1 : 0;
  EXPECT_GT(ahead, static_cast<int>(frames.size()) * 9 / 10);
}

}  // namespace
}  // namespace rgbdo
