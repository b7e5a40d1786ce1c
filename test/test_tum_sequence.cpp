#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <limits>
#include <opencv2/imgcodecs.hpp>

#include "rgbd_odometry/io/tum_sequence.hpp"
#include "rgbd_odometry/core/time_format.hpp"

namespace rgbdo {
namespace {

namespace fs = std::filesystem;

TEST(Timestamps, ParsedExactlyToNanoseconds) {
  EXPECT_EQ(parse_timestamp_ns("1305031102.175304"), 1305031102175304000LL);
  EXPECT_EQ(parse_timestamp_ns("12"), 12000000000LL);
  EXPECT_FALSE(parse_timestamp_ns("12.x"));
  EXPECT_FALSE(parse_timestamp_ns("-1.0"));
  EXPECT_EQ(format_seconds(1305031102175304000LL), "1305031102.175304");
}

TEST(TumSequence, BundledFramesAssociateWithin20ms) {
  const TumSequence seq = open_tum_sequence(RGBDO_TEST_DATA_DIR);
  ASSERT_EQ(seq.frames.size(), 40u);
  int shared_depth = 0;
  for (size_t i = 0; i < seq.frames.size(); ++i) {
    const auto& f = seq.frames[i];
    ASSERT_TRUE(f.t_depth_ns.has_value());
    EXPECT_LE(std::llabs(*f.t_depth_ns - f.t_colour_ns), 20'000'000);
    if (i > 0 && f.depth_path == seq.frames[i - 1].depth_path) ++shared_depth;
  }
  EXPECT_EQ(shared_depth, 7);  // see test/data/fr1_xyz/README.md
  EXPECT_FALSE(seq.groundtruth.empty());
}

TEST(TumSequence, LoadsFrameInMetres) {
  const TumSequence seq = open_tum_sequence(RGBDO_TEST_DATA_DIR);
  const RgbdFrame f = load_tum_frame(seq.frames[0], 5000, 640, 480);
  ASSERT_EQ(f.status, Status::Ok) << f.problem;
  EXPECT_EQ(f.gray.type(), CV_8UC1);
  EXPECT_EQ(f.depth_m.type(), CV_32FC1);
  double lo, hi;
  cv::minMaxLoc(f.depth_m, &lo, &hi);
  EXPECT_EQ(lo, 0.0);                  // holes stay 0
  EXPECT_NEAR(hi, 18587 / 5000.0, 1e-5);  // README.txt: first frame's max raw value
}

TEST(GroundTruth, InterpolatesBetweenSamplesAndRefusesGaps) {
  // Sampled every 10 ms, then a 40 ms gap (more than three intervals: the capture lost the
  // camera), then one of 0.93 s.
  std::vector<StampedPose> poses(6);
  const std::int64_t stamps_ms[] = {0, 10, 20, 30, 70, 1000};
  for (size_t i = 0; i < poses.size(); ++i) poses[i].t_ns = stamps_ms[i] * 1'000'000;
  poses[1].pose.translation() = Eigen::Vector3d(1, 0, 0);
  poses[1].pose.linear() = Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const GroundTruth gt(poses);
  EXPECT_EQ(groundtruth_gap_ns(poses), 30'000'000);
  const auto mid = gt.at(5'000'000);
  ASSERT_TRUE(mid);
  EXPECT_NEAR(mid->translation().x(), 0.5, 1e-12);
  EXPECT_NEAR(Eigen::AngleAxisd(mid->linear()).angle(), 0.1, 1e-12);
  EXPECT_TRUE(gt.at(25'000'000));
  EXPECT_TRUE(gt.at(70'000'000));    // a sample itself, at the gap's end
  EXPECT_FALSE(gt.at(50'000'000));   // inside the 40 ms gap
  EXPECT_FALSE(gt.at(500'000'000));  // inside the 0.93 s gap
  EXPECT_FALSE(gt.at(-1));
}

TEST(GroundTruth, GapThresholdOfTheLargestStampsDoesNotOverflow) {
  // Two samples 9e18 ns apart (the largest stamps parse_timestamp_ns takes): three such
  // intervals pass 64 bits, which UBSan flagged in fuzz_tum_sequence; with one interval
  // there is no gap to find, so the threshold saturates and the midpoint interpolates.
  std::vector<StampedPose> poses(2);
  poses[1].t_ns = 9'000'000'000'000'000'000;
  poses[1].pose.translation() = Eigen::Vector3d(2, 0, 0);
  EXPECT_EQ(groundtruth_gap_ns(poses), std::numeric_limits<std::int64_t>::max());
  const auto mid = GroundTruth(poses).at(4'500'000'000'000'000'000);
  ASSERT_TRUE(mid);
  EXPECT_NEAR(mid->translation().x(), 1.0, 1e-12);
}

class BrokenSequence : public ::testing::Test {
 protected:
  fs::path dir = fs::temp_directory_path() / ("rgbdo_tum_" + std::to_string(::getpid()));
  void SetUp() override { fs::create_directories(dir); }
  void TearDown() override { fs::remove_all(dir); }
  void write(const std::string& name, const std::string& text) { std::ofstream(dir / name) << text; }
};

TEST_F(BrokenSequence, MissingIndexNamesTheFile) {
  write("rgb.txt", "1.0 rgb/a.png\n");
  try {
    open_tum_sequence(dir.string());
    FAIL();
  } catch (const SourceError& e) {
    EXPECT_NE(std::string(e.what()).find("depth.txt"), std::string::npos) << e.what();
  }
}

TEST_F(BrokenSequence, MalformedLineNamesFileAndLine) {
  write("rgb.txt", "# header\n1.0 rgb/a.png\nabc rgb/b.png\n");
  write("depth.txt", "1.0 depth/a.png\n");
  try {
    open_tum_sequence(dir.string());
    FAIL();
  } catch (const SourceError& e) {
    EXPECT_NE(std::string(e.what()).find("rgb.txt:3"), std::string::npos) << e.what();
  }
}

TEST_F(BrokenSequence, CorruptWrongSizeAndMissingDepthAreFlaggedNotThrown) {
  fs::create_directories(dir / "rgb");
  fs::create_directories(dir / "depth");
  write("rgb/corrupt.png", "not a png at all");
  cv::imwrite((dir / "rgb/small.png").string(), cv::Mat(10, 10, CV_8UC3, cv::Scalar(1, 2, 3)));
  cv::imwrite((dir / "rgb/ok.png").string(), cv::Mat(480, 640, CV_8UC3, cv::Scalar(1, 2, 3)));
  cv::imwrite((dir / "depth/d8.png").string(), cv::Mat(480, 640, CV_8UC1, cv::Scalar(9)));
  write("rgb.txt", "1.00 rgb/corrupt.png\n1.10 rgb/small.png\n1.20 rgb/ok.png\n2.00 rgb/ok.png\n");
  write("depth.txt", "1.00 depth/d8.png\n1.10 depth/d8.png\n1.20 depth/d8.png\n");
  const TumSequence seq = open_tum_sequence(dir.string());
  ASSERT_EQ(seq.frames.size(), 4u);
  const auto corrupt = load_tum_frame(seq.frames[0], 5000, 640, 480);
  EXPECT_EQ(corrupt.status, Status::BadFrame);
  EXPECT_NE(corrupt.problem.find("corrupt.png"), std::string::npos);
  const auto small = load_tum_frame(seq.frames[1], 5000, 640, 480);
  EXPECT_EQ(small.status, Status::BadFrame);
  EXPECT_NE(small.problem.find("10x10"), std::string::npos);
  const auto eight_bit_depth = load_tum_frame(seq.frames[2], 5000, 640, 480);
  EXPECT_EQ(eight_bit_depth.status, Status::BadFrame);
  EXPECT_NE(eight_bit_depth.problem.find("16-bit"), std::string::npos);
  EXPECT_FALSE(seq.frames[3].t_depth_ns.has_value());  // 0.8 s from any depth frame
  EXPECT_EQ(load_tum_frame(seq.frames[3], 5000, 640, 480).status, Status::NoDepth);
}

TEST_F(BrokenSequence, AHugeFrameIsRefusedFromItsHeaderBeforeDecoding) {
  // A PNG declaring 20000 x 20000 (its decoding would take 1.2 GB): signature and IHDR only,
  // so the size in the message can only have come from the header.
  fs::create_directories(dir / "rgb");
  fs::create_directories(dir / "depth");
  const unsigned char header[33] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n', 0, 0, 0, 13, 'I', 'H', 'D', 'R',
                                    0, 0, 0x4E, 0x20, 0, 0, 0x4E, 0x20, 8, 2, 0, 0, 0, 0, 0, 0, 0};
  std::ofstream(dir / "rgb/huge.png", std::ios::binary).write(reinterpret_cast<const char*>(header), sizeof header);
  std::ofstream(dir / "depth/huge.png", std::ios::binary).write(reinterpret_cast<const char*>(header), sizeof header);
  cv::imwrite((dir / "rgb/ok.png").string(), cv::Mat(480, 640, CV_8UC3, cv::Scalar(1, 2, 3)));
  write("rgb.txt", "1.00 rgb/huge.png\n1.10 rgb/ok.png\n");
  write("depth.txt", "1.00 depth/huge.png\n1.10 depth/huge.png\n");
  const TumSequence seq = open_tum_sequence(dir.string());
  const auto colour = load_tum_frame(seq.frames[0], 5000, 640, 480);
  EXPECT_EQ(colour.status, Status::BadFrame);
  EXPECT_NE(colour.problem.find("20000x20000 (its PNG header; not decoded)"), std::string::npos) << colour.problem;
  const auto depth = load_tum_frame(seq.frames[1], 5000, 640, 480);
  EXPECT_EQ(depth.status, Status::BadFrame);
  EXPECT_NE(depth.problem.find("depth image"), std::string::npos) << depth.problem;
  EXPECT_NE(depth.problem.find("20000x20000"), std::string::npos) << depth.problem;
}

}  // namespace
}  // namespace rgbdo
