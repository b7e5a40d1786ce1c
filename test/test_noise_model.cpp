// The physical noise model's pieces: the per-point form and the capture-time error estimated
// from the streams' own stamps.
#include <gtest/gtest.h>

#include <cmath>

#include "rgbd_odometry/pipeline/noise_model.hpp"
#include "rgbd_odometry/core/rng.hpp"
#include "rgbd_odometry/pipeline/stamp_jitter.hpp"

namespace rgbdo {
namespace {

TEST(PhysicalPointNoise, KeypointErrorGrowsWithThePyramidLevelAcrossTheRay) {
  const SensorNoise model;  // 0.289 px at level 0, x1.2 per level, f = 525
  const Eigen::Vector3d p(0.3, -0.2, 2.0);
  const PointNoise level0 = physical_point_noise(p, 0, Eigen::Vector2d::Zero(), model);
  const PointNoise level5 = physical_point_noise(p, 5, Eigen::Vector2d::Zero(), model);
  EXPECT_NEAR(level0.lateral.x(), 0.289 * 2.0 / model.fx, 1e-12);
  EXPECT_NEAR(level5.lateral.x() / level0.lateral.x(), std::pow(1.2, 5), 1e-9);
  // The depth error lies along the viewing ray, sigma c Z^2 on flat depth, with the rounding
  // to the depth map's unit (TUM: 0.2 mm, uniform).
  EXPECT_NEAR(level0.ray.z(), std::hypot(1.425e-3 * 4.0, 0.2e-3 / std::sqrt(12.0)), 1e-12);
  EXPECT_NEAR(level0.ray.x() / level0.ray.z(), p.x() / p.z(), 1e-12);
  EXPECT_EQ(level0.ray, level5.ray);  // no slope: the pixel error does not reach the depth
}

TEST(PhysicalPointNoise, ExactDepthKeepsItsRoundingAndTheKeypointsSlopeError) {
  // A sensor with no depth noise at all and no lateral depth error (ICL-NUIM's rendering):
  // the ray's sigma never reaches zero, so the final fit's weights stay finite.
  SensorNoise exact;
  exact.depth_noise_coeff = 0;
  exact.depth_lateral_sigma_px = 0;
  const Eigen::Vector3d p(0, 0, 2.0);
  const PointNoise flat = physical_point_noise_px(p, 0.3, Eigen::Vector2d::Zero(), exact);
  EXPECT_NEAR(flat.ray.z(), 0.2e-3 / std::sqrt(12.0), 1e-15);
  const PointNoise steep = physical_point_noise_px(p, 0.3, Eigen::Vector2d(0.01, 0), exact);
  EXPECT_NEAR(steep.ray.z(), std::hypot(0.2e-3 / std::sqrt(12.0), 0.01 * 0.3), 1e-15);
  EXPECT_GT(steep.covariance().determinant(), 0);
}

TEST(PhysicalPointNoise, SteepDepthAddsThePixelAndDepthMapLateralErrors) {
  const SensorNoise model;
  const Eigen::Vector3d p(0, 0, 1.5);
  const Eigen::Vector2d slope(0.01, 0);  // 1 cm per pixel: an oblique surface
  const PointNoise flat = physical_point_noise(p, 2, Eigen::Vector2d::Zero(), model);
  const PointNoise steep = physical_point_noise(p, 2, slope, model);
  const double pixel = 0.289 * 1.2 * 1.2;
  const double expected = std::sqrt(std::pow(flat.ray.z(), 2) + 0.01 * 0.01 * (pixel * pixel + 0.8 * 0.8));
  EXPECT_NEAR(steep.ray.z(), expected, 1e-12);
  EXPECT_GT(steep.ray.z(), 2.5 * flat.ray.z());
}

TEST(PhysicalPointNoise, CovarianceIsTheLateralAndRayParts) {
  PointNoise n;
  n.lateral = {0.001, 0.002};
  n.ray = {0.0005, -0.001, 0.004};
  const Eigen::Matrix3d c = n.covariance();
  EXPECT_NEAR(c(0, 0), 1e-6 + 0.25e-6, 1e-15);
  EXPECT_NEAR(c(1, 1), 4e-6 + 1e-6, 1e-15);
  EXPECT_NEAR(c(0, 2), 0.0005 * 0.004, 1e-15);  // a depth error moves X and Z together
  EXPECT_NEAR(c(2, 2), 16e-6, 1e-15);
}

// Frames at a fixed period whose stamps carry Gaussian errors of the given sizes.
StampJitter jitter_of(double colour_sigma_s, double depth_sigma_s, int frames, int skip_every = 0) {
  Rng rng(5);
  StampJitter j;
  FrameTimes prev{};
  for (int i = 0; i < frames; ++i) {
    const int index = skip_every > 0 ? i + i / skip_every : i;  // a skipped frame now and then
    const double t = index / 30.0;
    FrameTimes now;
    now.t_colour_ns = static_cast<std::int64_t>((t + colour_sigma_s * rng.gaussian()) * 1e9);
    now.t_depth_ns = static_cast<std::int64_t>((t + 0.012 + depth_sigma_s * rng.gaussian()) * 1e9);
    if (i > 0) j.add(prev, now);
    prev = now;
  }
  return j;
}

TEST(StampJitter, RecoversTheStreamsStampErrors) {
  // 128 intervals per stream: the estimate's own scatter is ~9 %, so within 20 %.
  const double expected = std::hypot(0.0015, 0.002);
  EXPECT_NEAR(jitter_of(0.0015, 0.002, 400).offset_sigma_s(), expected, 0.2 * expected);
  EXPECT_NEAR(jitter_of(0.0005, 0.0, 400).offset_sigma_s(), 0.0005, 0.1e-3);
  // A hardware clock: microseconds.
  EXPECT_LT(jitter_of(0, 0, 400).offset_sigma_s(), 1e-6);
}

TEST(StampJitter, SkippedFramesAreNotStampError) {
  const double expected = std::hypot(0.001, 0.001);
  EXPECT_NEAR(jitter_of(0.001, 0.001, 400, 7).offset_sigma_s(), expected, 0.2 * expected);
}

TEST(StampJitter, NothingIsClaimedBeforeAFewIntervals) {
  EXPECT_EQ(jitter_of(0.002, 0.002, 3).offset_sigma_s(), 0.0);
}

}  // namespace
}  // namespace rgbdo
