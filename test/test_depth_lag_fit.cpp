// The depth's lag fitted to the pairs' differences against the gyro (pipeline/depth_lag_fit.cpp):
// a known lag and noise, the standard error it states, a failed fit left out.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "rgbd_odometry/pipeline/depth_lag_fit.hpp"

namespace rgbdo {
namespace {

constexpr double kLag = 0.012, kNoise = 2e-4;  // s; rad per component

struct Differences {
  std::mt19937 rng{11};
  std::normal_distribution<double> noise{0, kNoise}, slope{0, 0.3};  // rad/s: a hand-held camera's changes of rate
  Eigen::Vector3d g() { return {slope(rng), slope(rng), slope(rng)}; }
  Eigen::Vector3d y(const Eigen::Vector3d& g) { return kLag * g + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)); }
};

TEST(DepthLagFit, FindsTheLagAndStatesItsStandardError) {
  DepthLagFit fit;
  Differences d;
  double sum_gg = 0;
  for (int i = 0; i < 9; ++i) {
    const Eigen::Vector3d g = d.g();
    fit.add(d.y(g), g);
    sum_gg += g.squaredNorm();
  }
  EXPECT_FALSE(fit.known()) << "too few pairs for their scatter";
  for (int i = 0; i < 400; ++i) {
    const Eigen::Vector3d g = d.g();
    fit.add(d.y(g), g);
    sum_gg += g.squaredNorm();
  }
  ASSERT_TRUE(fit.known());
  EXPECT_EQ(fit.pairs(), 409u);
  const double expected_sigma = kNoise / std::sqrt(sum_gg);
  EXPECT_NEAR(fit.sigma_s(), expected_sigma, 0.1 * expected_sigma);
  EXPECT_NEAR(fit.lag_s(), kLag, 3 * expected_sigma);
}

TEST(DepthLagFit, LeavesAFailedFitOut) {
  DepthLagFit fit, clean;
  Differences a, b;  // the same draws for both
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d ga = a.g(), ya = a.y(ga), gb = b.g(), yb = b.y(gb);
    fit.add(ya, ga);
    clean.add(yb, gb);
    if (i == 100) fit.add(Eigen::Vector3d(0.05, -0.04, 0.03), Eigen::Vector3d(0.2, 0.1, -0.3));  // 3 degrees off
  }
  EXPECT_EQ(fit.rejected(), 1u);
  EXPECT_EQ(fit.pairs(), clean.pairs());
  EXPECT_DOUBLE_EQ(fit.lag_s(), clean.lag_s());
  fit.add(Eigen::Vector3d::Constant(NAN), Eigen::Vector3d::Ones());
  EXPECT_EQ(fit.pairs(), clean.pairs()) << "nothing learnt from a pair that is not a number";
}

}  // namespace
}  // namespace rgbdo
