#include <gtest/gtest.h>

#include <random>

#include "rgbd_odometry/core/geometry.hpp"
#include "rgbd_odometry/core/umeyama.hpp"

namespace rgbdo {
namespace {

Eigen::Isometry3d make_motion(double tx, double ty, double tz, double rx, double ry, double rz) {
  Vector6d xi;
  xi << tx, ty, tz, rx, ry, rz;
  return transform_from_xi(xi);
}

TEST(Umeyama, RecoversExactMotionFromNoiseFreePoints) {
  const Eigen::Isometry3d truth = make_motion(0.1, -0.2, 0.05, 0.3, -0.1, 0.2);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Eigen::Vector3d> src, dst;
  for (int i = 0; i < 20; ++i) {
    src.emplace_back(u(rng), u(rng), 2 + u(rng));
    dst.push_back(truth * src.back());
  }
  Eigen::Isometry3d T;
  ASSERT_TRUE(fit_rigid(src, dst, {}, T));
  EXPECT_LT((T.matrix() - truth.matrix()).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Umeyama, ClosedFormThreePointCase) {
  // GIVEN a right triangle rotated 90 degrees about z and shifted by (1, 2, 3)
  const std::vector<Eigen::Vector3d> src{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const std::vector<Eigen::Vector3d> dst{{1, 2, 3}, {1, 3, 3}, {0, 2, 3}};
  Eigen::Isometry3d T;
  ASSERT_TRUE(fit_rigid(src, dst, {}, T));
  Eigen::Matrix3d R_expected;
  R_expected << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  EXPECT_LT((T.linear() - R_expected).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((T.translation() - Eigen::Vector3d(1, 2, 3)).norm(), 1e-12);
}

TEST(Umeyama, NeverReturnsAReflection) {
  // A mirrored planar point set: the best proper rotation, det(R) = +1, must come out.
  const std::vector<Eigen::Vector3d> src{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0.1}};
  std::vector<Eigen::Vector3d> dst;
  for (const auto& p : src) dst.emplace_back(-p.x(), p.y(), p.z());
  Eigen::Isometry3d T;
  ASSERT_TRUE(fit_rigid(src, dst, {}, T));
  EXPECT_NEAR(T.linear().determinant(), 1.0, 1e-12);
}

TEST(Umeyama, WeightsSelectTheTrustedPoints) {
  // GIVEN two point groups that moved differently, one weighted 1e9 times less
  const Eigen::Isometry3d a = make_motion(0.1, 0, 0, 0, 0, 0), b = make_motion(-0.1, 0, 0, 0, 0, 0.1);
  const std::vector<Eigen::Vector3d> src{{0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {0, 0, 2},
                                         {1, 1, 2}, {2, 1, 1}, {1, 2, 3}, {3, 1, 2}};
  std::vector<Eigen::Vector3d> dst;
  std::vector<double> w;
  for (size_t i = 0; i < src.size(); ++i) {
    dst.push_back((i < 4 ? a : b) * src[i]);
    w.push_back(i < 4 ? 1.0 : 1e-9);
  }
  // THEN the fit follows the trusted group
  Eigen::Isometry3d T;
  ASSERT_TRUE(fit_rigid(src, dst, w, T));
  EXPECT_LT((T.matrix() - a.matrix()).cwiseAbs().maxCoeff(), 1e-6);
  // and with unit weights it does not
  ASSERT_TRUE(fit_rigid(src, dst, {}, T));
  EXPECT_GT((T.matrix() - a.matrix()).cwiseAbs().maxCoeff(), 1e-3);
}

TEST(Umeyama, RejectsCollinearAndTooFewPoints) {
  const std::vector<Eigen::Vector3d> line{{0, 0, 1}, {1, 1, 1}, {2, 2, 1}, {3, 3, 1}};
  Eigen::Isometry3d T;
  EXPECT_FALSE(fit_rigid(line, line, {}, T));
  const std::vector<Eigen::Vector3d> two{{0, 0, 1}, {1, 0, 1}};
  EXPECT_FALSE(fit_rigid(two, two, {}, T));
}

}  // namespace
}  // namespace rgbdo
