// A replay's gyro file (io/imu_file.cpp): what make_imu.py writes is read back exactly, extra
// columns and comments pass, and every malformed line is refused naming the file and line.
#include <gtest/gtest.h>

#include <array>
#include <filesystem>
#include <fstream>

#include "rgbd_odometry/io/imu_file.hpp"
#include "rgbd_odometry/io/tum_sequence.hpp"
#include "scratch_dir.hpp"

namespace rgbdo {
namespace {

std::string write(const ScratchDir& dir, const std::string& name, const std::string& text) {
  const std::filesystem::path p = dir.path() / name;
  std::ofstream(p) << text;
  return p.string();
}

std::string refusal(const std::string& text) {
  const ScratchDir dir("rgbdo_imu", "refusal");
  const std::string path = write(dir, "bad.txt", text);
  try {
    ImuFile file(path);
  } catch (const SourceError& e) {
    return e.what();
  }
  return "";
}

TEST(ImuFile, ReadsTheStampsExactlyAndTheRates) {
  const ScratchDir dir("rgbdo_imu", "read");
  // As make_imu.py writes it, with a line of extra columns and a blank one.
  ImuFile file(write(dir, "good.txt", "# timestamp wx wy wz (rad/s, body FRD), from groundtruth.txt by make_imu.py\n"
                                 "1305031098.685900 0.010000 -0.006000 0.008000\n"
                                 "\n"
                                 "1305031098.705900 0.5 -0.25 1e-3 99 extra columns\n"));
  ASSERT_EQ(file.samples().size(), 2u);
  EXPECT_EQ(file.samples()[0].t_ns, 1305031098'685900000LL);
  EXPECT_EQ(file.samples()[0].rate, Eigen::Vector3d(0.010, -0.006, 0.008));
  EXPECT_EQ(file.samples()[1].rate, Eigen::Vector3d(0.5, -0.25, 1e-3));
  // A clock of its own may start before zero (ICL's stamps begin at 0, a shifted gyro earlier).
  ImuFile early(write(dir, "early.txt", "-0.5 0.1 0.2 0.3\n-0.25 0 0 0\n0.000001 1 2 3\n"));
  ASSERT_EQ(early.samples().size(), 3u);
  EXPECT_EQ(early.samples()[0].t_ns, -500'000'000);
  EXPECT_EQ(early.samples()[1].t_ns, -250'000'000);
  EXPECT_EQ(early.samples()[2].t_ns, 1000);
}

TEST(ImuFile, HandsTheSamplesOutAsTheReplayReachesThem) {
  const ScratchDir dir("rgbdo_imu", "take");
  ImuFile file(write(dir, "take.txt", "1.0 0 0 0\n1.02 0 0 0\n1.04 0 0 0\n1.06 0 0 0\n"));
  std::array<GyroSample, 2> out;
  EXPECT_EQ(file.take(999'999'999, out), 0u);
  EXPECT_EQ(file.take(1'030'000'000, out), 2u);
  EXPECT_EQ(out[1].t_ns, 1'020'000'000);
  EXPECT_EQ(file.take(5'000'000'000, out), 2u) << "no more than the span holds";
  EXPECT_EQ(out[0].t_ns, 1'040'000'000);
  EXPECT_EQ(file.take(5'000'000'000, out), 0u);
  EXPECT_NE(file.description().find("4 samples, 50.0 Hz"), std::string::npos) << file.description();
}

TEST(ImuFile, EveryMalformedLineIsRefusedByFileAndLine) {
  EXPECT_NE(refusal("# only a comment\n").find("holds no samples"), std::string::npos);
  EXPECT_NE(refusal("1.0 0 0\n").find(":1: expected 'timestamp wx wy wz'"), std::string::npos);
  EXPECT_NE(refusal("# c\n1.0 0 0 zero\n").find(":2: bad angular rate 'zero'"), std::string::npos);
  EXPECT_NE(refusal("1.0 0 0 nan\n").find("bad angular rate 'nan'"), std::string::npos);
  EXPECT_NE(refusal("1,5 0 0 0\n").find(":1: bad timestamp '1,5'"), std::string::npos);
  EXPECT_NE(refusal("2.0 0 0 0\n2.0 0 0 0\n").find(":2: timestamp not after the line before"), std::string::npos);
  EXPECT_THROW(ImuFile("/nonexistent/imu.txt"), SourceError);
}

}  // namespace
}  // namespace rgbdo
