#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>

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
  ASSERT_EQ(h.size(), 11u + 36u + 1u + 21u);
  EXPECT_EQ(h[0], "t_prev");
  EXPECT_EQ(h[10], "qw");
  EXPECT_EQ(h[11], "c00");
  EXPECT_EQ(h[12], "c01");
  EXPECT_EQ(h[17], "c10");
  EXPECT_EQ(h[46], "c55");
  EXPECT_EQ(h[47], "chain");
  EXPECT_EQ(h[48], "pc00");
  EXPECT_EQ(h[54], "pc11");
  EXPECT_EQ(h[68], "pc55");
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
  ASSERT_EQ(f.size(), 69u);
  EXPECT_EQ(f[0], "1305031102.175304");
  EXPECT_EQ(f[1], "1305031102.211214");
  EXPECT_EQ(f[2], "ok");
  EXPECT_EQ(f[3], "321");
  EXPECT_DOUBLE_EQ(std::stod(f[5]), -0.02);
  EXPECT_NEAR(std::stod(f[8]), -std::sin(0.05), 1e-9);  // qy
  EXPECT_GT(std::stod(f[10]), 0);                        // qw >= 0 convention
  EXPECT_DOUBLE_EQ(std::stod(f[11 + 6 * 2 + 3]), 23);    // c23
  EXPECT_EQ(f[47], "0");                                 // no keyframe chain
  EXPECT_EQ(f[48], "nan");
}

TEST(OdometryCsv, AKeyframeChainCarriesTheUpperTriangleOfItsPoseCovariance) {
  PairResult r;
  r.t_prev_ns = 1'000'000'000;
  r.t_curr_ns = 1'033'333'333;
  r.keyframe.id = 4;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) r.keyframe.pose_covariance(i, j) = i * 10 + j;
  auto f = split(OdometryCsvWriter::row(r));
  EXPECT_EQ(f[47], "2");                               // going on
  EXPECT_DOUBLE_EQ(std::stod(f[48 + 1]), 1);           // pc01
  EXPECT_DOUBLE_EQ(std::stod(f[48 + 6 + 1]), 12);      // pc12: after row 0's six
  EXPECT_DOUBLE_EQ(std::stod(f[68]), 55);              // pc55
  r.keyframe.chain_started = true;
  f = split(OdometryCsvWriter::row(r));
  EXPECT_EQ(f[47], "1");
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
  ASSERT_EQ(f.size(), 69u);
  for (size_t k = 11; k < f.size(); ++k) EXPECT_EQ(f[k], k == 47 ? "0" : "nan") << "field " << k;
}

TEST(OdometryCsv, UnwritablePathIsNamed) {
  try {
    OdometryCsvWriter w("/nonexistent-dir/odometry.csv");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/odometry.csv"), std::string::npos);
  }
}

namespace fs = std::filesystem;

std::string read_all(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

struct Scratch {
  fs::path dir = fs::temp_directory_path() / ("rgbdo-logs-" + std::to_string(::getpid()));
  Scratch() {
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  ~Scratch() { fs::remove_all(dir); }
  std::string file(const char* name) const { return (dir / name).string(); }
};

PairResult failed_pair(std::int64_t t) {
  PairResult r;
  r.t_prev_ns = t;
  r.t_curr_ns = t + 33'000'000;
  r.status = Status::TooFewMatches;
  return r;
}

TEST(LogFiles, ARunKeepsTheEarlierRunsLogsNewestFirst) {
  const Scratch s;
  const std::string log = s.file("odometry.csv");
  std::vector<std::string> runs;
  for (int run = 0; run < 3; ++run) {
    OdometryCsvWriter w(log);
    for (int i = 0; i <= run; ++i) w.write(failed_pair(1'000'000'000LL * (run * 10 + i)));
    runs.push_back(read_all(log));
  }
  EXPECT_EQ(read_all(log), runs[2]);
  EXPECT_EQ(read_all(log + ".1"), runs[1]);
  EXPECT_EQ(read_all(log + ".2"), runs[0]);
  EXPECT_FALSE(fs::exists(log + ".3"));
  for (const auto& r : runs) EXPECT_EQ(r.rfind(OdometryCsvWriter::header() + "\n", 0), 0u);  // each opens with the header
}

TEST(LogFiles, TheLogsTogetherStayWithinTheBoundOldestRemovedFirst) {
  const Scratch s;
  const std::string path = s.file("trace.txt");
  const std::uint64_t bound = 10'000;
  std::string last;
  for (int run = 0; run < 3; ++run) {
    RotatingFile f(path, bound, "header");
    for (int i = 0; i < 400; ++i) {
      last = "run " + std::to_string(run) + " line " + std::to_string(i) + std::string(30, '.');
      f.write_line(last);
      std::uint64_t total = fs::file_size(path);
      for (int k = 1; fs::exists(path + "." + std::to_string(k)); ++k) total += fs::file_size(path + "." + std::to_string(k));
      ASSERT_LE(total, bound) << "run " << run << " line " << i;
    }
  }
  // The newest line is in FILE; every kept part opens with the header and holds whole lines
  // of the latest run (19,000 bytes written by it alone: the earlier runs are gone).
  const std::string newest = read_all(path);
  EXPECT_NE(newest.find(last + "\n"), std::string::npos);
  EXPECT_EQ(newest.rfind(last + "\n"), newest.size() - last.size() - 1);
  int kept = 0;
  for (int k = 1; fs::exists(path + "." + std::to_string(k)); ++k, ++kept) {
    const std::string part = read_all(path + "." + std::to_string(k));
    EXPECT_EQ(part.rfind("header\n", 0), 0u);
    EXPECT_EQ(part.back(), '\n');
    EXPECT_EQ(part.find("run 0"), std::string::npos);
  }
  EXPECT_GE(kept, 2);
}

TEST(LogFiles, ADeviceIsWrittenAsItIsNeverMoved) {
  RotatingFile f("/dev/null", 100, "header");
  for (int i = 0; i < 100; ++i) f.write_line("a line of text");
  EXPECT_TRUE(fs::exists("/dev/null"));
  EXPECT_FALSE(fs::exists("/dev/null.1"));
}

}  // namespace
}  // namespace rgbdo
