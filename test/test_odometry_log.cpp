#include <gtest/gtest.h>

#include <sstream>

#include "rgbd_odometry/io/odometry_log.hpp"

namespace rgbdo {
namespace {

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string f; std::getline(ss, f, ',');) out.push_back(f);
  return out;
}

TEST(OdometryCsv, HeaderIsTheDocumentedOne) {
  const auto h = split(OdometryCsvWriter::header());
  ASSERT_EQ(h.size(), 11u + 36u);
  EXPECT_EQ(h[0], "t_prev");
  EXPECT_EQ(h[10], "qw");
  EXPECT_EQ(h[11], "c00");
  EXPECT_EQ(h[12], "c01");
  EXPECT_EQ(h[17], "c10");
  EXPECT_EQ(h[46], "c55");
}

TEST(OdometryCsv, OkRowCarriesPoseAndRowMajorCovariance) {
  PairResult r;
  r.t_prev_ns = 1305031102175304000LL;
  r.t_curr_ns = 1305031102211214000LL;
  r.inliers = 321;
  r.T_prev_curr = Eigen::Translation3d(0.01, -0.02, 0.03) * Eigen::AngleAxisd(-0.1, Eigen::Vector3d::UnitY());
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) r.covariance(i, j) = i * 10 + j;
  const auto f = split(OdometryCsvWriter::row(r));
  ASSERT_EQ(f.size(), 47u);
  EXPECT_EQ(f[0], "1305031102.175304");
  EXPECT_EQ(f[1], "1305031102.211214");
  EXPECT_EQ(f[2], "ok");
  EXPECT_EQ(f[3], "321");
  EXPECT_DOUBLE_EQ(std::stod(f[5]), -0.02);
  EXPECT_NEAR(std::stod(f[8]), -std::sin(0.05), 1e-9);  // qy
  EXPECT_GT(std::stod(f[10]), 0);                        // qw >= 0 convention
  EXPECT_DOUBLE_EQ(std::stod(f[11 + 6 * 2 + 3]), 23);    // c23
}

TEST(OdometryCsv, FailedRowIsIdentityWithNanCovariance) {
  PairResult r;
  r.status = Status::TooFewMatches;
  r.inliers = 17;  // not reported for a failed pair
  r.T_prev_curr.translation() = Eigen::Vector3d(1, 2, 3);
  const auto f = split(OdometryCsvWriter::row(r));
  EXPECT_EQ(f[2], "too_few_matches");
  EXPECT_EQ(f[3], "0");
  EXPECT_EQ(f[4], "0");
  EXPECT_EQ(f[10], "1");
  for (size_t k = 11; k < f.size(); ++k) EXPECT_EQ(f[k], "nan");
}

TEST(OdometryCsv, UnwritablePathIsNamed) {
  try {
    OdometryCsvWriter w("/nonexistent-dir/odometry.csv");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/odometry.csv"), std::string::npos);
  }
}

}  // namespace
}  // namespace rgbdo
