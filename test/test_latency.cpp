// The capture-to-output latency summary (src/runtime/latency.cpp): nearest-rank quantiles to within
// a 0.1 ms bin, late samples kept in the last bin, and capture times ahead of the host clock
// counted apart instead of being summarised as zero latency.
#include <gtest/gtest.h>

#include <cmath>

#include "rgbd_odometry/runtime/latency.hpp"

namespace rgbdo {
namespace {

TEST(LatencyHistogram, QuantilesAreNearestRankToWithinABin) {
  LatencyHistogram h;
  for (int i = 1; i <= 100; ++i) h.add(i * 1.0);  // 1, 2, ... 100 ms
  EXPECT_EQ(h.count(), 100u);
  EXPECT_NEAR(h.quantile_ms(0.5), 50.0, LatencyHistogram::kBinMs);
  EXPECT_NEAR(h.quantile_ms(0.99), 99.0, LatencyHistogram::kBinMs);
  EXPECT_DOUBLE_EQ(h.quantile_ms(1.0), 100.0);
  EXPECT_DOUBLE_EQ(h.max_ms(), 100.0);
}

TEST(LatencyHistogram, AnEmptyHistogramSaysZeroAndCountsNothing) {
  const LatencyHistogram h;
  EXPECT_EQ(h.count(), 0u);
  EXPECT_EQ(h.quantile_ms(0.5), 0.0);
}

TEST(LatencyHistogram, LatenciesBeyondTheRangeKeepTheirMaximum) {
  LatencyHistogram h;
  h.add(10.0);
  h.add(5000.0);  // 5 s: beyond the 2 s of bins
  EXPECT_EQ(h.count(), 2u);
  EXPECT_DOUBLE_EQ(h.max_ms(), 5000.0);
  EXPECT_DOUBLE_EQ(h.quantile_ms(1.0), 5000.0);
  EXPECT_NEAR(h.quantile_ms(0.5), 10.0, LatencyHistogram::kBinMs);
}

TEST(LatencyHistogram, CaptureTimesAheadOfTheHostClockAreCountedApart) {
  LatencyHistogram h;
  h.add(-3.0);
  h.add(std::nan(""));
  h.add(20.0);
  EXPECT_EQ(h.count(), 1u);
  EXPECT_EQ(h.ahead_of_clock(), 2u);
  EXPECT_NEAR(h.quantile_ms(0.5), 20.0, LatencyHistogram::kBinMs);  // not pulled towards 0
}

}  // namespace
}  // namespace rgbdo
