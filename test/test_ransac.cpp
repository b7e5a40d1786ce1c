#include <gtest/gtest.h>

#include <random>

#include "rgbd_odometry/geometry.hpp"
#include "rgbd_odometry/ransac.hpp"
#include "rgbd_odometry/umeyama.hpp"

#include <Eigen/Cholesky>

namespace rgbdo {
namespace {

struct Scene {
  std::vector<Eigen::Vector3d> prev, curr;
  std::vector<bool> is_outlier;
};

// Points 1-3 m in front of the camera; prev = T * curr plus sensor-like noise; a fraction
// of the pairs replaced by wrong matches (random points of the same scene).
Scene make_scene(const Eigen::Isometry3d& T, int n, double outlier_fraction, double noise_m, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1), z(1, 3), unit(0, 1);
  std::normal_distribution<double> g(0, noise_m);
  Scene s;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d c(u(rng), 0.75 * u(rng), z(rng));
    s.curr.push_back(c);
    const bool outlier = unit(rng) < outlier_fraction;
    s.is_outlier.push_back(outlier);
    s.prev.push_back(outlier ? Eigen::Vector3d(u(rng), 0.75 * u(rng), z(rng))
                             : Eigen::Vector3d(T * c + Eigen::Vector3d(g(rng), g(rng), g(rng))));
  }
  return s;
}

RansacConfig paper_config() { return RansacConfig{}; }

TEST(Ransac, RecoversKnownMotionWithHalfTheMatchesWrong) {
  Vector6d xi;
  xi << 0.02, -0.01, 0.03, 0.01, -0.02, 0.015;
  const Eigen::Isometry3d truth = transform_from_xi(xi);
  const Scene s = make_scene(truth, 400, 0.5, 0.002, 7);
  RigidRansac ransac(paper_config(), SensorNoise{});
  Rng rng(1);
  const RansacResult r = ransac.estimate(s.prev, s.curr, rng);
  ASSERT_EQ(r.status, Status::Ok);
  const Eigen::Isometry3d err = truth.inverse() * r.T_prev_curr;
  EXPECT_LT(err.translation().norm(), 0.002);
  EXPECT_LT(rotation_angle(err.linear()), 0.002);
  // Inliers are the true ones: no planted outlier survives the refined threshold.
  int wrong = 0;
  for (int k : r.inliers) wrong += s.is_outlier[static_cast<size_t>(k)];
  EXPECT_LE(wrong, 2);  // a random point may land within the threshold by chance
  int true_inliers = 0;
  for (bool o : s.is_outlier) true_inliers += !o;
  EXPECT_GT(static_cast<int>(r.inliers.size()), 0.9 * true_inliers);
  EXPECT_LT(r.threshold_m, paper_config().inlier_threshold_m);  // refinement tightened it
}

TEST(Ransac, RayAlignedNoiseIsBetterFitAnisotropically) {
  // GIVEN correspondences whose noise is the sensor's: large along each viewing ray (depth),
  // small across it (pixels), and no outliers
  Vector6d xi;
  xi << 0.01, 0.005, -0.02, 0.004, -0.006, 0.003;
  const Eigen::Isometry3d truth = transform_from_xi(xi);
  const SensorNoise noise{1.425e-3, 0.25, 525};
  double err_plain = 0, err_aniso = 0;
  for (unsigned seed = 0; seed < 20; ++seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> g(0, 1);
    std::uniform_real_distribution<double> u(-1, 1), z(1, 4);
    std::vector<Eigen::Vector3d> prev, curr;
    const auto observe = [&](const Eigen::Vector3d& p) {
      const Eigen::Matrix3d L = point_covariance(p, noise).llt().matrixL();
      return Eigen::Vector3d(p + L * Eigen::Vector3d(g(rng), g(rng), g(rng)));
    };
    for (int i = 0; i < 150; ++i) {
      const Eigen::Vector3d c(u(rng) * 1.5, u(rng), z(rng));
      curr.push_back(observe(c));
      prev.push_back(observe(truth * c));
    }
    // WHEN fitted by RANSAC + refinement, and by one plain least-squares fit
    RigidRansac ransac(paper_config(), noise);
    Rng r(seed);
    const RansacResult fit = ransac.estimate(prev, curr, r);
    ASSERT_EQ(fit.status, Status::Ok);
    Eigen::Isometry3d plain;
    ASSERT_TRUE(fit_rigid(curr, prev, {}, plain));
    err_aniso += (xi_from_transform(truth.inverse() * fit.T_prev_curr)).squaredNorm();
    err_plain += (xi_from_transform(truth.inverse() * plain)).squaredNorm();
  }
  // THEN the noise-aware fit is clearly closer to the truth
  EXPECT_LT(err_aniso, 0.5 * err_plain);
}

TEST(Ransac, SameSeedSameAnswer) {
  const Scene s = make_scene(Eigen::Isometry3d::Identity(), 200, 0.4, 0.003, 9);
  RigidRansac a(paper_config(), SensorNoise{}), b(paper_config(), SensorNoise{});
  Rng ra(42), rb(42);
  const auto x = a.estimate(s.prev, s.curr, ra), y = b.estimate(s.prev, s.curr, rb);
  EXPECT_EQ(x.inliers, y.inliers);
  EXPECT_TRUE(x.T_prev_curr.isApprox(y.T_prev_curr, 0));
}

TEST(Ransac, AllPointsOnALineIsDegenerate) {
  std::vector<Eigen::Vector3d> line;
  for (int i = 0; i < 50; ++i) line.emplace_back(0.05 * i, 0.02 * i, 1.0 + 0.01 * i);
  RigidRansac ransac(paper_config(), SensorNoise{});
  Rng rng(1);
  EXPECT_EQ(ransac.estimate(line, line, rng).status, Status::DegenerateSample);
}

TEST(Ransac, PureNoiseHasTooFewInliers) {
  const Scene s = make_scene(Eigen::Isometry3d::Identity(), 100, 1.0, 0.0, 11);
  RigidRansac ransac(paper_config(), SensorNoise{});
  Rng rng(1);
  EXPECT_NE(ransac.estimate(s.prev, s.curr, rng).status, Status::Ok);
}

TEST(Ransac, FewerPairsThanMinimumFails) {
  const Scene s = make_scene(Eigen::Isometry3d::Identity(), 5, 0.0, 0.0, 13);
  RigidRansac ransac(paper_config(), SensorNoise{});
  Rng rng(1);
  EXPECT_EQ(ransac.estimate(s.prev, s.curr, rng).status, Status::RansacFailed);
}

}  // namespace
}  // namespace rgbdo
