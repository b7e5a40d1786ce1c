// The latency terms of the covariance (pipeline/latency_covariance.hpp) and the depth
// latency's response through the fit (PerturbationCovariance::depth_latency_response).
#include <gtest/gtest.h>

#include <random>

#include "rgbd_odometry/pipeline/noise_model.hpp"
#include "rgbd_odometry/core/rng.hpp"
#include "rgbd_odometry/core/umeyama.hpp"
#include "rgbd_odometry/pipeline/covariance.hpp"
#include "rgbd_odometry/pipeline/latency_covariance.hpp"

namespace rgbdo {
namespace {

Vector6d rate_of(double vx, double vy, double vz, double wx, double wy, double wz) {
  Vector6d r;
  r << vx, vy, vz, wx, wy, wz;
  return r;
}

// A pair measured far more precisely than any latency could matter.
PairRate precise(const Vector6d& rate, double dt_s = 1.0 / 30) {
  return {rate, 1e-14 * Matrix6d::Identity(), dt_s};
}

Matrix6d some_depth_response() {
  Matrix6d g = Matrix6d::Zero();
  g(2, 2) = 1.0;  // roughly what a scene facing the camera gives
  g(0, 4) = 0.4;
  g(1, 3) = -0.4;
  return g;
}

TEST(LatencyCovariance, AConstantRateAddsOnlyItsShareOfTheWindow) {
  // No change of rate, no per-pair error; over T_w the pairs' shares add up to
  // sigma^2 (r r^T + r r^T), the outer product of a change of rate as large as the rate.
  const Vector6d r = rate_of(0.2, -0.1, 0.05, 0.1, 0.3, -0.2);
  const LatencySigmas s{0.01, 0.0, 1.0};
  const PairRate pair = precise(r);
  EXPECT_LT(latency_covariance({0.01, 0.0, 0.0}, some_depth_response(), pair, pair).norm(), 1e-12);
  const Matrix6d share = latency_covariance(s, some_depth_response(), pair, pair);
  const Matrix6d window = 30 * share;  // 30 pairs of 1/30 s
  EXPECT_LT((window - 0.01 * 0.01 * 2 * r * r.transpose()).norm(), 1e-9 * window.norm());
}

TEST(LatencyCovariance, AChangeOfRateAddsItsOuterProductThroughBothLatencies) {
  const Vector6d before = rate_of(0.2, 0, 0.1, 0, 0.1, 0), after = rate_of(0.1, 0.05, -0.1, 0.2, 0.1, 0);
  const Matrix6d g = some_depth_response();
  const Matrix6d c = latency_covariance({0.01, 0.03, 0.0}, g, precise(after), precise(before));
  const Vector6d d = after - before;
  const Matrix6d expected = 1e-4 * d * d.transpose() + 9e-4 * g * d * d.transpose() * g.transpose();
  EXPECT_LT((c - expected).norm(), 1e-6 * expected.norm());
  // tz, through the depth response: 30 ms x a 0.2 m/s change, 6 mm; colour alone: 2 mm.
  EXPECT_NEAR(std::sqrt(c(2, 2)), std::hypot(0.01 * 0.2, 0.03 * 0.2), 1e-6);
}

TEST(LatencyCovariance, TheTranslationsOwnInstantEntersTheTranslationAlone) {
  // A pair restamped at its rotations' instant: its translations' instant is apart by up to
  // sigma_t, which adds sigma_t^2 D_t D_t^T to the translation block and nothing else.
  const PairRate prev{rate_of(0.1, 0, 0, 0, 0.2, 0), Matrix6d::Zero(), 1.0 / 30};
  const PairRate curr{rate_of(0.3, -0.1, 0, 0.1, 0.1, 0), Matrix6d::Zero(), 1.0 / 30};
  LatencySigmas s{0.002, 0.0, 0.0};
  const Matrix6d without = latency_covariance(s, Matrix6d::Zero(), curr, prev);
  s.translation_s = 0.01;
  const Matrix6d with = latency_covariance(s, Matrix6d::Zero(), curr, prev);
  const Eigen::Vector3d change_t = (curr.rate - prev.rate).head<3>();  // stretch 1: equal intervals
  const Matrix6d added = with - without;
  EXPECT_LT((added.topLeftCorner<3, 3>() - 1e-4 * change_t * change_t.transpose()).norm(), 1e-12);
  EXPECT_EQ(added.bottomRows(3).norm(), 0.0);
  EXPECT_EQ(added.topRightCorner(3, 3).norm(), 0.0);
}

// The image of a point straight ahead at depth z, the camera moving at `rate` (xi / dt of
// T_prev_curr): its shift per second in normalised image coordinates, from where the point is
// seen after a short step (p' = T^-1 p), not from the formula under test.
Eigen::Vector2d image_shift_rate(const Vector6d& rate, double z) {
  constexpr double step = 1e-6;
  const Eigen::Vector3d moved = transform_from_xi(rate * step).inverse() * Eigen::Vector3d(0, 0, z);
  return Eigen::Vector2d(moved.x() / moved.z(), moved.y() / moved.z()) / step;
}

TEST(LatencyCovariance, ARestampedPairCarriesItsImageShiftsChangeTimesTheLatencyApplied) {
  // Stamps moved by L = 14 ms, the image shift not: what the pair is off by is L times the
  // change of the image's rate, as a rotation of the same image shift (an image shift dx is a
  // rotation -dx about y, dy one of +dy about x).
  const double L = 0.014, z = 1.25;
  const Vector6d before = rate_of(0.1, 0.02, 0, 0.05, 0.2, 0), after = rate_of(0.3, -0.1, 0.05, 0.1, -0.1, 0.02);
  PairRate prev = precise(before), curr = precise(after);
  curr.inverse_depth = 1 / z;
  LatencySigmas s{0, 0, 0};
  s.image_shift_off_s = L;
  const Matrix6d c = latency_covariance(s, Matrix6d::Zero(), curr, prev);
  const Eigen::Vector2d shift = image_shift_rate(after, z) - image_shift_rate(before, z);
  const Eigen::Vector2d as_rotation(shift.y(), -shift.x());  // (rx, ry)
  const Eigen::Matrix2d expected = L * L * as_rotation * as_rotation.transpose();
  EXPECT_LT((c.block<2, 2>(3, 3) - expected).norm(), 1e-3 * expected.norm());
  Matrix6d elsewhere = c;
  elsewhere.block<2, 2>(3, 3).setZero();
  EXPECT_EQ(elsewhere.norm(), 0.0);
  // A change along the slide (translation and rotation that leave the image where it was)
  // moves no image: nothing to carry. Nor does a pair whose stamps were not moved.
  const Vector6d slide = after + rate_of(0.2, 0.1, 0, 0.1 / z, -0.2 / z, 0);
  EXPECT_LT(latency_covariance(s, Matrix6d::Zero(), PairRate{slide, curr.covariance, curr.dt_s, 1 / z}, PairRate{after, curr.covariance, curr.dt_s, 1 / z})
                .norm(),
            1e-12);
  s.image_shift_off_s = 0;
  EXPECT_EQ(latency_covariance(s, Matrix6d::Zero(), curr, prev).norm(), 0.0);
}

TEST(LatencyCovariance, ThePairsOwnNoiseIsNotTakenForAChangeOfRate) {
  // Two pairs at the same rate, each measured with noise C: the difference of their measured
  // rates is noise, var 2 C / dt^2. Plain D D^T would report it as a change; what is kept
  // must be a fraction of that, while a true change twenty times the noise comes through
  // nearly whole.
  const double dt = 1.0 / 30;
  const Matrix6d C = Vector6d(rate_of(1, 1, 1, 1, 1, 1) * 1e-3).cwiseAbs2().asDiagonal();  // sigma 1 mm, 1 mrad
  const LatencySigmas s{0.01, 0.0, 0.0};
  std::mt19937 gen(7);
  std::normal_distribution<double> n01;
  double kept = 0, plain = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    Vector6d a, b;
    for (int i = 0; i < 6; ++i) {
      a(i) = 1e-3 * n01(gen) / dt;
      b(i) = 1e-3 * n01(gen) / dt;
    }
    kept += latency_covariance(s, Matrix6d::Zero(), {a, C, dt}, PairRate{b, C, dt}).trace();
    plain += 1e-4 * (a - b).squaredNorm();
  }
  EXPECT_LT(kept, 0.26 * plain);  // E[(chi2_6 - 6)+] / 6 = 0.22
  const Vector6d change = 20 * std::sqrt(2.0) * 1e-3 / dt * rate_of(1, 0, 0, 0, 0, 0);
  const Matrix6d c = latency_covariance(s, Matrix6d::Zero(), {change, C, dt}, PairRate{Vector6d::Zero(), C, dt});
  EXPECT_GT(c(0, 0), 0.97 * 1e-4 * change(0) * change(0));
  EXPECT_LT(c(0, 0), 1e-4 * change(0) * change(0));
}

TEST(LatencyCovariance, WithoutAPreviousPairTheChangeIsTakenAsLargeAsTheRate) {
  const Vector6d r = rate_of(0.3, 0, 0, 0, 0, 0.5);
  const Matrix6d c = latency_covariance({0.01, 0.0, 0.0}, Matrix6d::Zero(), precise(r), std::nullopt);
  EXPECT_LT((c - 1e-4 * r * r.transpose()).norm(), 1e-6 * c.norm());
  EXPECT_EQ(latency_covariance({0.0, 0.0, 1.0}, some_depth_response(), precise(r), std::nullopt), Matrix6d::Zero());
}

TEST(DepthLatencyResponse, PredictsTheFitOfDepthsReadLateWhileTheRateChanges) {
  // A static scene seen from a camera whose rate changes from `before` to `after` between
  // the two frames. Each frame's depths are read delta late, Z - delta dZ/dt under its own
  // rate; nothing else is wrong. The fitted motion is off by about -delta G (after - before).
  std::mt19937 gen(11);
  std::uniform_real_distribution<double> u(-1, 1), z(1.0, 3.5);
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 300; ++i) pts.emplace_back(z(gen) * Eigen::Vector3d(0.55 * u(gen), 0.4 * u(gen), 1.0));
  const Vector6d before = rate_of(0.1, -0.05, 0.25, 0.2, -0.3, 0.1), after = rate_of(-0.1, 0.05, -0.2, -0.3, 0.3, 0.0);
  const double delta = 0.03;
  const auto read_late = [&](const Vector6d& rate) {
    std::vector<Eigen::Vector3d> out;
    for (const auto& p : pts) {
      const double dz_dt = -(rate.head<3>() + rate.tail<3>().cross(p)).z();
      out.push_back(p * (1.0 - delta * dz_dt / p.z()));  // along the ray
    }
    return out;
  };
  const auto prev = read_late(before), curr = read_late(after);

  CovarianceConfig config;
  config.perturbations = 16;
  PerturbationCovariance pc(config, 300);
  std::vector<PointNoise> noise;
  for (const auto& p : pts) noise.push_back(physical_point_noise(p, 0, Eigen::Vector2d::Zero(), SensorNoise{}));
  Rng rng(1);
  Matrix6d cov;
  ASSERT_TRUE(pc.estimate(pts, pts, noise, noise, {}, Eigen::Isometry3d::Identity(), 0.0, rng, cov));
  const Matrix6d g = pc.depth_latency_response(pts, pts);

  std::vector<double> w;
  for (const auto& p : pts) w.push_back(pair_weight(p, p, config.depth_noise_coeff));
  Eigen::Isometry3d T;
  ASSERT_TRUE(fit_rigid(curr, prev, w, T));
  const Vector6d error = xi_from_transform(T);
  const Vector6d predicted = -delta * g * (after - before);
  EXPECT_GT(error.norm(), 5e-3);  // millimetres and milliradians: not a vanishing effect
  EXPECT_LT((error - predicted).norm(), 0.05 * error.norm()) << error.transpose() << "\n" << predicted.transpose();
  EXPECT_NEAR(g(2, 2), 1.0, 0.1);  // depths read late while approaching at v_z: tz off by delta v_z
}

}  // namespace
}  // namespace rgbdo
