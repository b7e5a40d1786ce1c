// LearntConstant: the rule a learnt sensor constant follows (warm-up mean with the prior,
// then a bounded step), on readings whose answers are known by hand. What each user reads
// from real residuals is tested with it: test_keypoint_sigma, test_depth_alignment.
#include <gtest/gtest.h>

#include <cmath>

#include "rgbd_odometry/pipeline/learnt_constant.hpp"

namespace rgbdo {
namespace {

constexpr LearntConstantRule kSmoothed{
    .averaged_readings = 3, .geometric = false, .gain = 0.25, .max_step = 0.5, .min = 0.1, .max = 100};

TEST(LearntConstant, ItsWarmUpIsTheMeanOfThePriorAndTheReadings) {
  LearntConstant arithmetic(1.0, kSmoothed);
  arithmetic.add(3.0);
  EXPECT_DOUBLE_EQ(arithmetic.value(), 2.0);
  arithmetic.add(5.0);
  arithmetic.add(7.0);
  EXPECT_DOUBLE_EQ(arithmetic.value(), 4.0);  // (1 + 3 + 5 + 7) / 4

  LearntConstantRule rule = kSmoothed;
  rule.geometric = true;
  LearntConstant geometric(1.0, rule);
  geometric.add(100.0);
  EXPECT_NEAR(geometric.value(), 10.0, 1e-12);
  geometric.add(10.0);
  geometric.add(10.0);
  EXPECT_NEAR(geometric.value(), std::pow(1e4, 0.25), 1e-12);  // (1 * 100 * 10 * 10)^(1/4)
}

TEST(LearntConstant, AfterItEachReadingMovesItByItsGainAtMostItsBound) {
  LearntConstant c(4.0, kSmoothed);
  for (int k = 0; k < 3; ++k) c.add(4.0);
  c.add(6.0);
  EXPECT_DOUBLE_EQ(c.value(), 4.5);  // a quarter of the difference
  c.add(100.0);
  EXPECT_DOUBLE_EQ(c.value(), 6.75);  // half of itself, not a quarter of 95.5
  c.add(0.1);
  EXPECT_DOUBLE_EQ(c.value(), 6.75 - 0.25 * 6.65);
}

TEST(LearntConstant, ReadingsThatSayNothingAreNotCountedAndItKeepsItsBounds) {
  LearntConstant c(1.0, kSmoothed);
  c.add(std::nan(""));
  c.add(-1.0);
  c.add(INFINITY);
  EXPECT_DOUBLE_EQ(c.value(), 1.0);
  c.add(3.0);
  EXPECT_DOUBLE_EQ(c.value(), 2.0);  // still the first reading of the warm-up
  for (int k = 0; k < 200; ++k) c.add(1e9);
  EXPECT_DOUBLE_EQ(c.value(), 100.0);
  for (int k = 0; k < 200; ++k) c.add(0.0);
  EXPECT_DOUBLE_EQ(c.value(), 0.1);
  EXPECT_DOUBLE_EQ(LearntConstant(1e-9, kSmoothed).value(), 0.1);  // a prior outside is brought in
}

}  // namespace
}  // namespace rgbdo
