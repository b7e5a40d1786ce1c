#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "rgbd_odometry/rng.hpp"

namespace rgbdo {
namespace {

// Produced by this generator for seed 1 on x86-64. The integers must match exactly on every
// architecture. The gaussian goes through libm's log, whose last bits differ between
// glibc's x86-64 and armhf builds (measured: 12 ulp on this value), so it gets 1e-14.
constexpr std::uint32_t kGoldenFirst = 3019024837u;
constexpr std::uint32_t kGoldenBelow = 520u;
constexpr double kGoldenGaussian = 0x1.88c0ad8d8854dp-3;

TEST(Rng, SameSequenceOnEveryArchitecture) {
  // These values are this generator's output for seed 1. The same test runs natively and
  // on armhf under qemu: both must reproduce them, bit for bit, or replays would diverge.
  Rng r(1);
  const std::uint32_t expected[4] = {r.next_u32(), r.next_u32(), r.next_u32(), r.next_u32()};
  Rng again(1);
  for (auto e : expected) EXPECT_EQ(again.next_u32(), e);
  Rng golden(1);
  EXPECT_EQ(golden.next_u32(), kGoldenFirst);
  EXPECT_EQ(golden.below(1000), kGoldenBelow);
  EXPECT_NEAR(golden.gaussian(), kGoldenGaussian, 1e-14);
}

TEST(Rng, BelowStaysInRangeAndCoversIt) {
  Rng r(7);
  std::vector<int> hits(7, 0);
  for (int i = 0; i < 70000; ++i) {
    const auto v = r.below(7);
    ASSERT_LT(v, 7u);
    ++hits[v];
  }
  for (int h : hits) EXPECT_NEAR(h, 10000, 500);  // > 5 sigma of a binomial(70000, 1/7)
}

TEST(Rng, GaussianHasUnitMomentsAndTails) {
  Rng r(3);
  const int n = 200000;
  double sum = 0, sq = 0;
  int beyond2 = 0;
  for (int i = 0; i < n; ++i) {
    const double x = r.gaussian();
    sum += x;
    sq += x * x;
    beyond2 += std::abs(x) > 2;
  }
  EXPECT_NEAR(sum / n, 0.0, 0.01);
  EXPECT_NEAR(sq / n, 1.0, 0.01);
  EXPECT_NEAR(static_cast<double>(beyond2) / n, 0.0455, 0.002);
}

TEST(Rng, Uniform01IsInTheHalfOpenUnitInterval) {
  Rng r(5);
  double lo = 1, hi = 0;
  for (int i = 0; i < 100000; ++i) {
    const double u = r.uniform01();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    lo = std::min(lo, u);
    hi = std::max(hi, u);
  }
  EXPECT_LT(lo, 1e-3);
  EXPECT_GT(hi, 1 - 1e-3);
}

}  // namespace
}  // namespace rgbdo
