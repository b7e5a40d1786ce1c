// The autopilot's ATTITUDE rates onto our clock (link/autopilot_gyro.cpp): mapped through the
// TIMESYNC offset, held back and counted before it is known, the oldest lost (and counted) when
// nobody takes them, forgotten for another autopilot.
#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "rgbd_odometry/link/autopilot_gyro.hpp"

namespace rgbdo {
namespace {

TEST(AutopilotGyro, RatesAreMappedOntoOurClockThroughTheOffset) {
  AutopilotGyro g;
  const std::int64_t offset = 1'234'567'000'000;  // autopilot clock - ours
  g.add(5'000, 0.1f, -0.2f, 0.3f, std::nullopt);  // before the offset is known
  g.add(1'240'000, 0.5f, 0.25f, -0.125f, offset);
  g.add(1'240'020, 0.f, 0.f, NAN, offset);  // not a rate
  std::array<GyroSample, 8> out;
  ASSERT_EQ(g.take(0, out), 1u) << "live: whatever has arrived, whatever until_ns says";
  EXPECT_EQ(out[0].t_ns, 1'240'000LL * 1'000'000 - offset);
  EXPECT_EQ(out[0].rate, Eigen::Vector3d(0.5, 0.25, -0.125));
  EXPECT_EQ(g.counts().received, 2u);
  EXPECT_EQ(g.counts().unmapped, 1u);
  EXPECT_EQ(g.take(0, out), 0u);
  EXPECT_NE(g.description().find("ATTITUDE"), std::string::npos);
}

TEST(AutopilotGyro, AReaderThatFallsBehindLosesTheOldestCounted) {
  AutopilotGyro g;
  for (std::uint32_t ms = 1; ms <= 1100; ++ms) g.add(ms, 0.f, 0.f, static_cast<float>(ms), 0);
  std::array<GyroSample, 2000> out;
  const std::size_t n = g.take(0, out);
  EXPECT_EQ(n, 1024u);
  EXPECT_EQ(g.counts().overwritten, 76u);
  EXPECT_EQ(out[0].rate.z(), 77.0) << "oldest first, after the lost ones";
  EXPECT_EQ(out[n - 1].rate.z(), 1100.0);
  g.add(2000, 0.f, 0.f, 0.f, 0);
  g.clear();  // another autopilot
  EXPECT_EQ(g.take(0, out), 0u);
}

}  // namespace
}  // namespace rgbdo
