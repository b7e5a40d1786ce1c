// Every compiled FAST-9 kernel this CPU supports against the scalar reference, flag for flag:
// run lengths at lane boundaries, unaligned starts, thresholds at the ends of the range
// (saturation), random and real images, and a known corner; the score kernels likewise, and
// against scores worked out by hand.
#include <gtest/gtest.h>

#include <array>
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

// Blocky noise: `noise` magnified 4x from its top-left corner; plateaus make long arcs, so
// corners are common (a flat-noise image has few).
cv::Mat blocky_from(const cv::Mat& noise) {
  cv::Mat blocky(noise.size(), CV_8UC1);
  for (int y = 0; y < blocky.rows; ++y)
    for (int x = 0; x < blocky.cols; ++x) blocky.at<std::uint8_t>(y, x) = noise.at<std::uint8_t>(y / 4, x / 4);
  return blocky;
}

TEST(FastKernels, BitExactAtLaneBoundariesAndThresholdExtremes) {
  cv::Mat noise(24, 120, CV_8UC1);
  cv::randu(noise, 0, 256);
  cv::Mat blocky = blocky_from(noise);
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

// The 16 circle offsets at an image's row step, as the extractor passes them.
std::array<std::ptrdiff_t, 16> circle_offsets(const cv::Mat& image) {
  std::array<std::ptrdiff_t, 16> offsets{};
  for (int k = 0; k < 16; ++k)
    offsets[static_cast<size_t>(k)] = simd::kFastCircle[k][1] * static_cast<std::ptrdiff_t>(image.step) + simd::kFastCircle[k][0];
  return offsets;
}

TEST(FastKernels, ScoreTwinsAreBitExactOverEveryPixelFlagAndThreshold) {
  cv::Mat noise(16, 40, CV_8UC1);
  cv::randu(noise, 0, 256);
  cv::Mat blocky = blocky_from(noise);
  // Centres at both ends of the range, where centre +- threshold leaves [0, 255].
  noise.at<std::uint8_t>(5, 10) = 0;
  noise.at<std::uint8_t>(6, 12) = 255;
  for (const cv::Mat* image : {&noise, &blocky}) {
    const auto offsets = circle_offsets(*image);
    for (int y = 3; y < image->rows - 3; ++y)
      for (int x = 3; x < image->cols - 3; ++x) {
        const std::uint8_t* p = image->ptr<std::uint8_t>(y) + x;
        for (const int threshold : {0, 1, 7, 20, 100, 254, 255, 300})
          for (const int flags : {1, 2, 3}) {
            const int expected = simd::fast9_score_scalar(p, offsets.data(), threshold, flags);
            for (const auto* set : twins_of_reference(&simd::KernelSet::fast9_score))
              ASSERT_EQ(set->fast9_score(p, offsets.data(), threshold, flags), expected)
                  << set->name << " at (" << x << ", " << y << "), threshold " << threshold << ", flags " << flags;
          }
      }
  }
}

TEST(FastKernels, TheScoreIsTheFlaggedSidesExcessOverTheThreshold) {
  // A centre of 10 with 9 circle pixels at 200 (the rest at 10), threshold 20: each bright one
  // exceeds 10 + 20 by 170, so the bright side scores 9 x 170; nothing is darker than -10.
  cv::Mat bright(7, 7, CV_8UC1, cv::Scalar(10));
  for (int k = 0; k < 9; ++k) bright.at<std::uint8_t>(3 + simd::kFastCircle[k][1], 3 + simd::kFastCircle[k][0]) = 200;
  // A centre of 200 with 10 circle pixels at 10 (the rest at 200), threshold 20: 10 x 170 dark.
  cv::Mat dark(7, 7, CV_8UC1, cv::Scalar(200));
  for (int k = 4; k < 14; ++k) dark.at<std::uint8_t>(3 + simd::kFastCircle[k][1], 3 + simd::kFastCircle[k][0]) = 10;
  for (const auto* set : sets_with_own(&simd::KernelSet::fast9_score)) {
    const auto score = [&](const cv::Mat& image, int flags) {
      return set->fast9_score(image.ptr<std::uint8_t>(3) + 3, circle_offsets(image).data(), 20, flags);
    };
    EXPECT_EQ(score(bright, 1), 9 * 170) << set->name;
    EXPECT_EQ(score(bright, 2), 0) << set->name << ": no darker side";
    EXPECT_EQ(score(bright, 3), 9 * 170) << set->name;
    EXPECT_EQ(score(dark, 2), 10 * 170) << set->name;
    EXPECT_EQ(score(dark, 1), 0) << set->name << ": no brighter side";
  }
}

}  // namespace
}  // namespace rgbdo
