// KeypointSigmaEstimate: each level's keypoint localisation read back from reprojection
// residuals of a known law, its prior, its averaging then its rate, its bounds.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "rgbd_odometry/pipeline/keypoint_sigma.hpp"

namespace rgbdo {
namespace {

// The residual of a match whose two keypoints are each off by N(0, sigma^2) in u and v.
double residual_px(std::mt19937& rng, double sigma_px) {
  std::normal_distribution<double> g(0, sigma_px);
  return std::hypot(g(rng) - g(rng), g(rng) - g(rng));
}

TEST(KeypointSigma, StartsAtTheConfiguredLawLevelByLevel) {
  const KeypointSigmaEstimate e(0.289, 1.2, 8, 500);
  EXPECT_DOUBLE_EQ(e.sigma_px(0), 0.289);
  EXPECT_NEAR(e.sigma_px(7), 0.289 * std::pow(1.2, 7), 1e-12);
  EXPECT_DOUBLE_EQ(e.sigma_px(12), e.sigma_px(7));  // beyond the pyramid: its coarsest level
  EXPECT_DOUBLE_EQ(e.sigma_px(-1), e.sigma_px(0));
}

TEST(KeypointSigma, ReadsBackTheLocalisationOfEachLevel) {
  // GIVEN keypoints localised to 0.5 px at level 0 and 1.1 px at level 5 (a blurred camera),
  // 40 matches of each a pair
  KeypointSigmaEstimate e(0.289, 1.2, 8, 500);
  std::mt19937 rng(3);
  for (int pair = 0; pair < 60; ++pair) {
    for (int k = 0; k < 40; ++k) {
      e.add(0, residual_px(rng, 0.5));
      e.add(5, residual_px(rng, 1.1));
    }
    e.update();
  }
  // THEN each level reads its own law within a few per cent; a level with no residuals keeps its prior
  EXPECT_NEAR(e.sigma_px(0), 0.5, 0.5 * 0.05);
  EXPECT_NEAR(e.sigma_px(5), 1.1, 1.1 * 0.05);
  EXPECT_DOUBLE_EQ(e.sigma_px(3), 0.289 * std::pow(1.2, 3));
}

TEST(KeypointSigma, FirstReadingsAreAveragedThenEachMovesItByAtMostItsRate) {
  KeypointSigmaEstimate e(1.0, 1.2, 8, 100);
  // The first reading averaged with the prior (counted as one): a reading of 3 px gives 2.
  const double median_per_sigma = std::sqrt(2.0 * std::log(2.0)) * std::sqrt(2.0);
  for (int k = 0; k < 9; ++k) e.add(0, 3.0 * median_per_sigma);
  e.update();
  EXPECT_NEAR(e.sigma_px(0), 2.0, 1e-6);
  for (int pair = 0; pair < 9; ++pair) {  // readings 2 ... 10
    for (int k = 0; k < 9; ++k) e.add(0, 2.0 * median_per_sigma);
    e.update();
  }
  EXPECT_NEAR(e.sigma_px(0), 2.0, 1e-6);
  // After ten readings a wild one moves it by 10 % at most, either way.
  for (int k = 0; k < 9; ++k) e.add(0, 40.0 * median_per_sigma);
  e.update();
  EXPECT_NEAR(e.sigma_px(0), 2.2, 1e-6);
  for (int k = 0; k < 9; ++k) e.add(0, 0.0);
  e.update();
  EXPECT_NEAR(e.sigma_px(0), 2.2 * 0.9, 1e-6);
}

TEST(KeypointSigma, FewResidualsBadLevelsAndNonFiniteValuesChangeNothing) {
  KeypointSigmaEstimate e(0.289, 1.2, 4, 100);
  for (int k = 0; k < KeypointSigmaEstimate::kMinResiduals - 1; ++k) e.add(1, 5.0);  // too few for a reading
  e.add(4, 5.0);   // no such level
  e.add(-1, 5.0);
  for (int k = 0; k < 20; ++k) e.add(2, std::nan(""));
  e.update();
  for (int l = 0; l < 4; ++l) EXPECT_DOUBLE_EQ(e.sigma_px(l), 0.289 * std::pow(1.2, l)) << "level " << l;
}

TEST(KeypointSigma, StaysWithinItsBounds) {
  KeypointSigmaEstimate e(0.289, 1.2, 2, 100);
  for (int pair = 0; pair < 100; ++pair) {
    for (int k = 0; k < 10; ++k) e.add(0, 0.0), e.add(1, 1e6);
    e.update();
  }
  EXPECT_DOUBLE_EQ(e.sigma_px(0), KeypointSigmaEstimate::kMinSigma_px);
  EXPECT_DOUBLE_EQ(e.sigma_px(1), KeypointSigmaEstimate::kMaxSigma_px);
}

TEST(KeypointSigma, KeepsAtMostItsCapacityAPair) {
  // More residuals than the capacity (features.max_features) are not stored: no allocation.
  KeypointSigmaEstimate e(1.0, 1.2, 1, 10);
  const double median_per_sigma = std::sqrt(2.0 * std::log(2.0)) * std::sqrt(2.0);
  for (int k = 0; k < 1000; ++k) e.add(0, k < 10 ? 0.5 * median_per_sigma : 100.0);
  e.update();
  EXPECT_NEAR(e.sigma_px(0), 0.75, 1e-6);  // the first ten (0.5 px) averaged with the prior
}

}  // namespace
}  // namespace rgbdo
