#include <gtest/gtest.h>

#include <random>

#include "rgbd_odometry/covariance.hpp"
#include "rgbd_odometry/noise_model.hpp"
#include "rgbd_odometry/umeyama.hpp"

namespace rgbdo {
namespace {

std::vector<Eigen::Vector3d> scene(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1), z(1, 3);
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < n; ++i) pts.emplace_back(u(rng), 0.75 * u(rng), z(rng));
  return pts;
}

CovarianceConfig paper_config(int perturbations) {
  CovarianceConfig c;
  c.perturbations = perturbations;
  c.scale = 1.0;
  c.residual_variance_factor = false;
  return c;
}

// Independent Monte-Carlo: draw fresh noisy observations of the TRUE clouds (not of one
// noisy realisation), fit each, and take the spread of the fitted motions.
Matrix6d monte_carlo_covariance(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                                int trials) {
  Rng rng(12345);
  const auto g = [](Rng& r) { return r.gaussian(); };
  std::vector<double> w;
  for (size_t k = 0; k < prev.size(); ++k) w.push_back(pair_weight(prev[k], curr[k], 1.425e-3));
  std::vector<Vector6d> xs;
  std::vector<Eigen::Vector3d> np(prev.size()), nc(curr.size());
  for (int t = 0; t < trials; ++t) {
    for (size_t k = 0; k < prev.size(); ++k) {
      np[k] = prev[k] + point_sigma(prev[k], 1.425e-3).cwiseProduct(Eigen::Vector3d(g(rng), g(rng), g(rng)));
      nc[k] = curr[k] + point_sigma(curr[k], 1.425e-3).cwiseProduct(Eigen::Vector3d(g(rng), g(rng), g(rng)));
    }
    Eigen::Isometry3d T;
    EXPECT_TRUE(fit_rigid(nc, np, w, T));
    xs.push_back(xi_from_transform(T));
  }
  Vector6d mean = Vector6d::Zero();
  for (const auto& x : xs) mean += x;
  mean /= trials;
  Matrix6d c = Matrix6d::Zero();
  for (const auto& x : xs) c += (x - mean) * (x - mean).transpose();
  return c / (trials - 1);
}

TEST(PerturbationCovariance, AgreesWithIndependentMonteCarlo) {
  // GIVEN 150 point pairs related by a small motion, without noise
  Vector6d xi;
  xi << 0.01, -0.02, 0.015, 0.01, 0.005, -0.01;
  const Eigen::Isometry3d T = transform_from_xi(xi);
  const auto curr = scene(150, 1);
  std::vector<Eigen::Vector3d> prev;
  for (const auto& c : curr) prev.push_back(T * c);
  // WHEN the pipeline's perturbation covariance uses many perturbations
  PerturbationCovariance pc(paper_config(4000));
  Rng rng(7);
  Matrix6d cov;
  ASSERT_TRUE(pc.estimate(prev, curr, T, rng, cov));
  const Matrix6d mc = monte_carlo_covariance(prev, curr, 4000);
  // THEN each variance is within 10 % (sampling error of 4000 draws is ~2.2 % per variance)
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(cov(i, i) / mc(i, i), 1.0, 0.1) << "axis " << i;
  // and the correlations agree to 0.1
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < i; ++j)
      EXPECT_NEAR(cov(i, j) / std::sqrt(cov(i, i) * cov(j, j)), mc(i, j) / std::sqrt(mc(i, i) * mc(j, j)), 0.1);
}

TEST(PerturbationCovariance, TranslationVarianceFollowsTheNoiseModelAnalytically) {
  // n points on the plane Z = 2, symmetric about the optical axis. To first order tz is the
  // weighted mean of the Z noise of both clouds (rotations move the on-axis centroid only
  // sideways), so var(tz) = 2 sigma_Z^2 sum(w^2) / (sum w)^2 with the fit's weights w.
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 400; ++i) pts.emplace_back(0.04 * (i % 20 - 9.5), 0.04 * (i / 20 - 9.5), 2.0);
  double sw = 0, sw2 = 0;
  for (const auto& p : pts) {
    const double w = pair_weight(p, p, 1.425e-3);
    sw += w;
    sw2 += w * w;
  }
  const double sigma_z = 1.425e-3 * 4.0;
  const double expected = 2 * sigma_z * sigma_z * sw2 / (sw * sw);
  PerturbationCovariance pc(paper_config(3000));
  Rng rng(3);
  Matrix6d cov;
  ASSERT_TRUE(pc.estimate(pts, pts, Eigen::Isometry3d::Identity(), rng, cov));
  EXPECT_NEAR(cov(2, 2) / expected, 1.0, 0.1);  // 3000 draws: ~2.6 % sampling error
}

TEST(PerturbationCovariance, ResultIsSymmetricPositiveDefiniteAndScaled) {
  const auto curr = scene(60, 2);
  CovarianceConfig config = paper_config(100);
  PerturbationCovariance unscaled(config);
  config.scale = 9.0;
  PerturbationCovariance scaled(config);
  Rng r1(5), r2(5);
  Matrix6d a, b;
  ASSERT_TRUE(unscaled.estimate(curr, curr, Eigen::Isometry3d::Identity(), r1, a));
  ASSERT_TRUE(scaled.estimate(curr, curr, Eigen::Isometry3d::Identity(), r2, b));
  EXPECT_TRUE(is_valid_covariance(a));
  EXPECT_TRUE(a.isApprox(a.transpose(), 0));
  EXPECT_TRUE((b - 9.0 * a).cwiseAbs().maxCoeff() < 1e-12 * b.cwiseAbs().maxCoeff());
}

TEST(PerturbationCovariance, VarianceFactorGrowsWithResiduals) {
  const auto curr = scene(100, 4);
  std::vector<Eigen::Vector3d> noisy = curr;
  std::mt19937 rng(1);
  std::normal_distribution<double> g(0, 0.02);  // far noisier than the model's ~mm
  for (auto& p : noisy) p += Eigen::Vector3d(g(rng), g(rng), g(rng));
  const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
  EXPECT_DOUBLE_EQ(PerturbationCovariance::variance_factor(curr, curr, I, 1.425e-3), 1.0);  // floored
  EXPECT_GT(PerturbationCovariance::variance_factor(noisy, curr, I, 1.425e-3), 10.0);
}

TEST(CovarianceValidity, RejectsNonFiniteAsymmetricAndIndefinite) {
  Matrix6d c = Matrix6d::Identity();
  EXPECT_TRUE(is_valid_covariance(c));
  c(0, 1) = 0.5;
  EXPECT_FALSE(is_valid_covariance(c));  // asymmetric
  c = Matrix6d::Identity();
  c(3, 3) = -1;
  EXPECT_FALSE(is_valid_covariance(c));
  c(3, 3) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(is_valid_covariance(c));
}

}  // namespace
}  // namespace rgbdo
