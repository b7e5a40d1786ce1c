#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

#include "rgbd_odometry/core/rng.hpp"
#include "rgbd_odometry/core/splitmix64.hpp"

namespace rgbdo {
namespace {

// Published outputs of Blackman & Vigna's reference implementation (xoshiro128starstar.c,
// version 1.1), from a state given word by word:
// - state {1, 2, 3, 4}: the first ten outputs, as listed in the test of the rand_xoshiro
//   crate ("produced with the reference implementation");
// - state {0x964D4A0C, 0xD40AB895, 0xAD7FDECB, 0x3006F0F0}: four outputs and the state after
//   them, as listed in the test data of xoshiro-6502 (generated with the C reference).
TEST(Rng, Xoshiro128StarStarMatchesTheReferenceImplementation) {
  Rng small({1, 2, 3, 4});
  const std::uint32_t expected_small[10] = {11520u,      0u,          5927040u,    70819200u,   2031721883u,
                                            1637235492u, 1287239034u, 3734860849u, 3729100597u, 4258142804u};
  for (const auto e : expected_small) EXPECT_EQ(small.next_u32(), e);

  Rng mixed({0x964D4A0Cu, 0xD40AB895u, 0xAD7FDECBu, 0x3006F0F0u});
  const std::uint32_t expected_mixed[4] = {0xF1391922u, 0x6FE53806u, 0xA5BE2840u, 0xF510EE70u};
  for (const auto e : expected_mixed) EXPECT_EQ(mixed.next_u32(), e);
  // The same state as the reference's after those four steps: the next output from it.
  Rng after({0xFC65379Cu, 0x52006D70u, 0x87487639u, 0xF1908343u});
  EXPECT_EQ(mixed.next_u32(), after.next_u32());
}

// Seeding is ours (splitmix64 expanding a 64-bit seed); its outputs must be the same on every
// architecture or replays would diverge between the x86 CI and the Odroid. This test runs
// natively and on armhf under qemu. These values are splitmix64's first outputs for seed 1
// (upper halves), cross-checked against the published splitmix64 first output for seed 0,
// 0xE220A8397B1DCDAF.
TEST(Rng, SeedingExpandsTheSeedWithSplitMix64) {
  std::uint64_t state = 0;
  EXPECT_EQ(splitmix64_next(state), 0xE220A8397B1DCDAFULL);
  Rng seeded(1);
  std::uint64_t sm = 1;
  std::array<std::uint32_t, 4> words{};
  for (auto& w : words) w = static_cast<std::uint32_t>(splitmix64_next(sm) >> 32);
  Rng from_words(words);
  for (int i = 0; i < 8; ++i) EXPECT_EQ(seeded.next_u32(), from_words.next_u32());
}

// libm's log differs in its last bits between glibc's x86-64 and armhf builds (measured: 12
// ulp on this value), so the gaussian of seed 1 gets 1e-14, where a changed algorithm moves
// it by far more.
TEST(Rng, DerivedDrawsAreStable) {
  Rng golden(1);
  EXPECT_EQ(golden.next_u32(), 3019024837u);
  EXPECT_EQ(golden.below(1000), 520u);
  EXPECT_NEAR(golden.gaussian(), 0x1.88c0ad8d8854dp-3, 1e-14);
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
