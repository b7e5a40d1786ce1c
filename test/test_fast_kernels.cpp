// Every compiled FAST-9 kernel this CPU supports against the scalar reference, flag for flag:
// run lengths at lane boundaries, unaligned starts, thresholds at the ends of the range
// (saturation), random and real images, and a known corner.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "rgbd_odometry/io/tum_sequence.hpp"
#include "rgbd_odometry/simd/kernels.hpp"
#include "runnable_kernel_sets.hpp"

namespace rgbdo {
namespace {

// Flags of every set over rows [3, rows - 3) from column `start`, n pixels, against scalar.
void expect_same_as_scalar(const cv::Mat& image, int start, int n, int threshold, const std::string& what) {
  std::vector<std::uint8_t> expected(static_cast<size_t>(n) + 1, 0xAA), got(static_cast<size_t>(n) + 1, 0xAA);
  for (int y = 3; y < image.rows - 3; ++y) {
    const std::uint8_t* row = image.ptr<std::uint8_t>(y) + start;
    simd::fast9_row_scalar(row, static_cast<std::ptrdiff_t>(image.step), n, threshold, expected.data());
    ASSERT_EQ(expected[static_cast<size_t>(n)], 0xAA) << "the reference wrote past n";
    for (const auto* set : twins_of_reference(&simd::KernelSet::fast9_row)) {
      std::fill(got.begin(), got.end(), 0xAA);
      set->fast9_row(row, static_cast<std::ptrdiff_t>(image.step), n, threshold, got.data());
      ASSERT_EQ(got, expected) << set->name << ", " << what << ", row " << y << ", start " << start << ", n " << n
                               << ", threshold " << threshold;
    }
  }
}

TEST(FastKernels, BitExactAtLaneBoundariesAndThresholdExtremes) {
  cv::Mat noise(24, 120, CV_8UC1);
  cv::randu(noise, 0, 256);
  // Blocky noise: plateaus make long arcs, so corners are common (a flat-noise image has few).
  cv::Mat blocky(noise.size(), CV_8UC1);
  for (int y = 0; y < blocky.rows; ++y)
    for (int x = 0; x < blocky.cols; ++x) blocky.at<std::uint8_t>(y, x) = noise.at<std::uint8_t>(y / 4, x / 4);
  for (const cv::Mat* image : {&noise, &blocky})
    for (const int n : {0, 1, 15, 16, 17, 31, 32, 33, 47, 64, 65, 100})
      for (const int start : {3, 4, 7})
        for (const int threshold : {0, 1, 7, 20, 100, 254, 255, 300})
          expect_same_as_scalar(*image, start, n, threshold, image == &noise ? "noise" : "blocky");
}

TEST(FastKernels, BitExactOnRealFrames) {
  const TumSequence seq = open_tum_sequence(RGBDO_TEST_DATA_DIR);
  for (const int index : {0, 20, 39}) {
    const RgbdFrame f = load_tum_frame(seq.frames[static_cast<size_t>(index)], 5000, 640, 480);
    for (const int threshold : {7, 20}) expect_same_as_scalar(f.gray, 3, 640 - 6, threshold, "frame " + std::to_string(index));
  }
}

TEST(FastKernels, FindTheCornerOfABrightSquare) {
  cv::Mat image(20, 40, CV_8UC1, cv::Scalar(10));
  cv::rectangle(image, cv::Rect(20, 10, 20, 10), cv::Scalar(200), cv::FILLED);
  for (const auto* set : sets_with_own(&simd::KernelSet::fast9_row)) {
    std::vector<std::uint8_t> flags(34);
    // Row 10 from column 3: the square's top-left corner is at x = 20, i.e. flags[17].
    set->fast9_row(image.ptr<std::uint8_t>(10) + 3, static_cast<std::ptrdiff_t>(image.step), 34, 20, flags.data());
    EXPECT_EQ(flags[17], 2) << set->name << ": the corner pixel, darker all round outside the square";
    EXPECT_EQ(flags[5], 0) << set->name << ": flat background";
  }
}

}  // namespace
}  // namespace rgbdo
