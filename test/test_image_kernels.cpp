// The image kernels (rgbd_odometry/simd/image.hpp): every compiled set this CPU supports
// against the scalar reference, byte for byte, at run lengths around the vector widths, at
// the weights' ends and on the floats a NEON compare would get wrong (denormals, -0, NaN);
// and the references against independent definitions (OpenCV's integral image and inRange).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <vector>

#include "rgbd_odometry/simd/kernels.hpp"
#include "runnable_kernel_sets.hpp"

namespace rgbdo {
namespace {

std::vector<std::uint8_t> random_bytes(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<std::uint8_t> v(n);
  for (auto& b : v) b = static_cast<std::uint8_t>(rng());
  return v;
}

constexpr int kRunLengths[] = {0, 1, 7, 8, 9, 15, 16, 17, 31, 33, 100, 533};

TEST(ImageKernels, BlendRowsIsTheRoundedWeightedMeanInEverySet) {
  const auto r0 = random_bytes(600, 1), r1 = random_bytes(600, 2);
  for (const auto* set : sets_with_own(&simd::KernelSet::blend_rows))
    for (unsigned w : {0u, 1u, 77u, 128u, 255u, 256u})
      for (int n : kRunLengths) {
        std::vector<std::uint8_t> got(static_cast<size_t>(n) + 1, 0xAB);
        set->blend_rows(r0.data() + 1, r1.data() + 3, n, w, got.data());
        for (int i = 0; i < n; ++i) {
          const double exact = (r0[static_cast<size_t>(i) + 1] * (256.0 - w) + r1[static_cast<size_t>(i) + 3] * w) / 256.0;
          ASSERT_EQ(got[static_cast<size_t>(i)], static_cast<int>(std::floor(exact + 0.5)))
              << set->name << " w " << w << " n " << n << " i " << i;
        }
        EXPECT_EQ(got.back(), 0xAB) << set->name << " wrote past n";
      }
}

TEST(ImageKernels, ResampleRowGathersAndBlendsAsTheReference) {
  std::mt19937 rng(3);
  const auto src = random_bytes(2000, 4);
  for (int n : kRunLengths) {
    // Groups as a downscale by 1.01 to 2 makes them: increasing bases, indices up to 14.
    std::vector<simd::ResampleGroup> groups(static_cast<size_t>((n + 7) / 8));
    int base = 0;
    for (auto& g : groups) {
      g.base = base;
      int x = static_cast<int>(rng() % 2);
      for (int k = 0; k < 8; ++k) {
        g.index[k] = static_cast<std::uint8_t>(x);
        g.weight[k] = static_cast<std::uint8_t>(k == 0 ? 0 : k == 1 ? 255 : rng() % 256);
        x = std::min(x + 1 + static_cast<int>(rng() % 2), 14);
      }
      base += 10 + static_cast<int>(rng() % 5);
    }
    std::vector<std::uint8_t> want(static_cast<size_t>(n) + 1, 0xAB);
    simd::resample_row_scalar(src.data(), groups.data(), n, want.data());
    for (int i = 0; i < n; ++i) {
      const auto& g = groups[static_cast<size_t>(i / 8)];
      const int a = src[static_cast<size_t>(g.base + g.index[i % 8])], b = src[static_cast<size_t>(g.base + g.index[i % 8] + 1)];
      const int w = g.weight[i % 8];
      ASSERT_EQ(want[static_cast<size_t>(i)], (a * (256 - w) + b * w + 128) >> 8);
    }
    for (const auto* set : sets_with_own(&simd::KernelSet::resample_row)) {
      std::vector<std::uint8_t> got(static_cast<size_t>(n) + 1, 0xAB);
      set->resample_row(src.data(), groups.data(), n, got.data());
      EXPECT_EQ(got, want) << set->name << " n " << n;
    }
  }
}

TEST(ImageKernels, Box5RowSumsTheFiveByFiveNeighbourhood) {
  cv::Mat image(9, 560, CV_8UC1);
  cv::randu(image, 0, 256);
  image.row(4).colRange(100, 140).setTo(255);  // the largest sums: 25 * 255 fits 16 bits
  image.rowRange(2, 7).colRange(100, 140).setTo(255);
  cv::Mat integral;
  cv::integral(image, integral, CV_32S);
  for (int start : {2, 3, 5, 11}) {
    for (int n : kRunLengths) {
      if (start + n + 2 > image.cols) continue;
      const std::uint8_t* centre = image.ptr<std::uint8_t>(4) + start;
      std::vector<std::uint16_t> want(static_cast<size_t>(n) + 1, 0xABCD);
      simd::box5_row_scalar(centre, static_cast<std::ptrdiff_t>(image.step), n, want.data());
      for (int i = 0; i < n; ++i) {
        const int x = start + i;
        const int sum = integral.at<int>(7, x + 3) - integral.at<int>(2, x + 3) - integral.at<int>(7, x - 2) + integral.at<int>(2, x - 2);
        ASSERT_EQ(want[static_cast<size_t>(i)], sum) << "start " << start << " i " << i;
      }
      for (const auto* set : sets_with_own(&simd::KernelSet::box5_row)) {
        std::vector<std::uint16_t> got(static_cast<size_t>(n) + 1, 0xABCD);
        set->box5_row(centre, static_cast<std::ptrdiff_t>(image.step), n, got.data());
        EXPECT_EQ(got, want) << set->name << " start " << start << " n " << n;
      }
    }
  }
}

TEST(ImageKernels, SurfaceMeanAveragesOneSurfaceAndKeepsTheCentreElsewhere) {
  // A noisy slanted plane (2-4 m, Kinect-like noise) with holes and a 20 cm step down its
  // middle column; samples everywhere 2 pixels in from the border.
  const int width = 64, height = 48;
  std::vector<float> depth(static_cast<size_t>(width * height));
  std::mt19937 rng(11);
  std::normal_distribution<float> noise(0.0f, 1.0f);
  std::uniform_int_distribution<int> hole(0, 40);
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const float z = 2.0f + 0.03f * static_cast<float>(u) + (u >= 32 ? 0.2f : 0.0f);
      depth[static_cast<size_t>(v * width + u)] = hole(rng) == 0 ? 0.0f : z + 1.425e-3f * z * z * noise(rng);
    }
  std::vector<std::int32_t> centre;
  for (int v = 2; v < height - 2; ++v)
    for (int u = 2; u < width - 2; ++u) centre.push_back(v * width + u);
  const int n = static_cast<int>(centre.size());
  const float spread = 0.06f;
  std::vector<float> want(centre.size() + 1, -1.0f);
  simd::surface_mean5_scalar(depth.data(), width, centre.data(), n, spread, want.data());
  EXPECT_EQ(want.back(), -1.0f) << "wrote past n";
  int averaged = 0, kept = 0;
  for (size_t k = 0; k < centre.size(); ++k) {
    const int u0 = centre[k] % width, v0 = centre[k] / width;
    double sum = 0, lo = 1e9, hi = -1e9;
    for (int v = v0 - 2; v <= v0 + 2; ++v)
      for (int u = u0 - 2; u <= u0 + 2; ++u) {
        const double z = depth[static_cast<size_t>(v * width + u)];
        sum += z, lo = std::min(lo, z), hi = std::max(hi, z);
      }
    const float c = depth[static_cast<size_t>(centre[k])];
    if (lo > 0 && hi - lo <= spread * c) {
      ++averaged;
      ASSERT_NEAR(want[k], sum / 25, 1e-6) << "sample " << k;
    } else {
      ++kept;
      ASSERT_EQ(want[k], c) << "sample " << k << ": a hole or the step in its window";
    }
  }
  EXPECT_GT(averaged, n / 3);
  EXPECT_GT(kept, n / 10);
  for (const auto* set : sets_with_own(&simd::KernelSet::surface_mean5))
    for (int count : {0, 1, 3, 4, 5, n}) {
      std::vector<float> got(static_cast<size_t>(count) + 1, -1.0f);
      set->surface_mean5(depth.data(), width, centre.data(), count, spread, got.data());
      for (int k = 0; k < count; ++k)
        ASSERT_EQ(got[static_cast<size_t>(k)], want[static_cast<size_t>(k)]) << set->name << " sample " << k;  // bit-exact
      EXPECT_EQ(got.back(), -1.0f) << set->name << " wrote past n";
    }
}

TEST(ImageKernels, DepthInRangeFollowsInRangeOnEveryFloat) {
  const float denormal = std::numeric_limits<float>::denorm_min();
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  std::vector<float> depth = {0.0f, -0.0f, denormal, -denormal, 1e-39f, -1e-39f, 0.5f, 0.4f, 4.0f, 4.0000005f,
                              nan, -nan, inf, -inf, 1.0f, 3.9999998f, 0.49999997f, 100.0f, -1.0f};
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.0f, 6.0f);
  while (depth.size() < 203) depth.push_back(u(rng));
  for (const auto& [lo, hi] : {std::pair{0.5f, 4.0f}, std::pair{0.0f, 4.0f}, std::pair{denormal, 0.5f}}) {
    for (int n : {0, 1, 7, 8, 9, 16, 17, 19, 33, 203}) {
      std::vector<std::uint8_t> want(static_cast<size_t>(n) + 1, 0xAB);
      simd::depth_in_range_row_scalar(depth.data(), n, lo, hi, want.data());
      for (int i = 0; i < n; ++i) {
        const float d = depth[static_cast<size_t>(i)];
        ASSERT_EQ(want[static_cast<size_t>(i)], (d >= lo && d <= hi) ? 255 : 0) << d;
      }
      if (n > 0) {
        // OpenCV's own rule for the finite values (its NaN handling is its own business).
        cv::Mat in(1, n, CV_32FC1, depth.data()), mask;
        cv::inRange(in, lo, hi, mask);
        for (int i = 0; i < n; ++i) {
          if (!std::isfinite(depth[static_cast<size_t>(i)])) continue;
          ASSERT_EQ(mask.at<std::uint8_t>(0, i), want[static_cast<size_t>(i)]) << depth[static_cast<size_t>(i)];
        }
      }
      for (const auto* set : sets_with_own(&simd::KernelSet::depth_in_range_row)) {
        std::vector<std::uint8_t> got(static_cast<size_t>(n) + 1, 0xAB);
        set->depth_in_range_row(depth.data(), n, lo, hi, got.data());
        EXPECT_EQ(got, want) << set->name << " lo " << lo << " n " << n;
      }
    }
  }
}

TEST(ImageKernels, DiscMomentsAreTheIntensityCentroidSums) {
  // Random texture, a saturated patch (the largest sums) and a ramp (a known centroid
  // direction), at centres whose disc touches the allowed margins.
  cv::Mat image(64, 80, CV_8UC1);
  cv::randu(image, 0, 256);
  image(cv::Rect(40, 20, 30, 30)).setTo(255);
  for (int y = 0; y < 64; ++y) image.at<std::uint8_t>(y, 79) = 0;
  for (const auto& [cx, cy] : {std::pair{16, 15}, std::pair{64, 48}, std::pair{50, 30}, std::pair{33, 33}}) {
    const std::uint8_t* centre = image.ptr<std::uint8_t>(cy) + cx;
    std::int32_t want10 = 0, want01 = 0;
    for (int dy = -15; dy <= 15; ++dy)
      for (int dx = -15; dx <= 15; ++dx)
        if (dx * dx + dy * dy <= 225) {
          want10 += dx * image.at<std::uint8_t>(cy + dy, cx + dx);
          want01 += dy * image.at<std::uint8_t>(cy + dy, cx + dx);
        }
    for (const auto* set : sets_with_own(&simd::KernelSet::disc_moments)) {
      std::int32_t m10 = 7, m01 = 7;
      set->disc_moments(centre, static_cast<std::ptrdiff_t>(image.step), &m10, &m01);
      EXPECT_EQ(m10, want10) << set->name << " at " << cx << "," << cy;
      EXPECT_EQ(m01, want01) << set->name << " at " << cx << "," << cy;
    }
  }
  // A horizontal ramp: the centroid lies to the right (m10 > 0), level (m01 = 0).
  cv::Mat ramp(40, 40, CV_8UC1);
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 40; ++x) ramp.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(5 * x);
  for (const auto* set : sets_with_own(&simd::KernelSet::disc_moments)) {
    std::int32_t m10 = 0, m01 = 7;
    set->disc_moments(ramp.ptr<std::uint8_t>(20) + 20, static_cast<std::ptrdiff_t>(ramp.step), &m10, &m01);
    EXPECT_GT(m10, 0) << set->name;
    EXPECT_EQ(m01, 0) << set->name;
  }
}

TEST(ImageKernels, ColourToGrayIsOpenCvsConversion) {
  // Random colours, the extremes, and a real frame of the bundled recording; both channel
  // orders; run lengths around the vector width.
  cv::Mat colour(7, 533, CV_8UC3);
  cv::randu(colour, 0, 256);
  colour.row(0).setTo(cv::Scalar(255, 255, 255));
  colour.row(1).setTo(cv::Scalar(0, 0, 0));
  const cv::Mat real = cv::imread(RGBDO_TEST_DATA_DIR "/rgb/1305031102.175304.png", cv::IMREAD_COLOR);
  ASSERT_FALSE(real.empty());
  for (const cv::Mat* image : {static_cast<const cv::Mat*>(&colour), &real})
    for (const bool red_first : {false, true}) {
      cv::Mat want;
      cv::cvtColor(*image, want, red_first ? cv::COLOR_RGB2GRAY : cv::COLOR_BGR2GRAY);
      for (const auto* set : sets_with_own(&simd::KernelSet::colour_to_gray_row))
        for (int n : {0, 1, 7, 8, 9, 17, image->cols}) {
          std::vector<std::uint8_t> got(static_cast<size_t>(n) + 1, 0xAB);
          for (int y = 0; y < image->rows; ++y) {
            set->colour_to_gray_row(image->ptr<std::uint8_t>(y), n, red_first, got.data());
            for (int i = 0; i < n; ++i)
              ASSERT_EQ(got[static_cast<size_t>(i)], want.at<std::uint8_t>(y, i)) << set->name << " row " << y << " i " << i;
            ASSERT_EQ(got.back(), 0xAB);
          }
        }
    }
}

TEST(ImageKernels, DepthToMetresIsConvertTosProduct) {
  cv::Mat raw(3, 203, CV_16UC1);
  cv::randu(raw, 0, 65536);
  raw.at<std::uint16_t>(0, 0) = 0;
  raw.at<std::uint16_t>(0, 1) = 65535;
  for (const double units_per_m : {5000.0, 1000.0, 1e6, 1e-3, 3.7}) {
    cv::Mat want;
    raw.convertTo(want, CV_32F, 1.0 / units_per_m);
    for (const auto* set : sets_with_own(&simd::KernelSet::depth_to_metres_row))
      for (int n : {0, 1, 7, 8, 9, 203}) {
        std::vector<float> got(static_cast<size_t>(n) + 1, -1.0f);
        for (int y = 0; y < raw.rows; ++y) {
          set->depth_to_metres_row(raw.ptr<std::uint16_t>(y), n, static_cast<float>(1.0 / units_per_m), got.data());
          for (int i = 0; i < n; ++i)
            ASSERT_EQ(got[static_cast<size_t>(i)], want.at<float>(y, i)) << set->name << " " << units_per_m << " i " << i;
          ASSERT_EQ(got.back(), -1.0f);
        }
      }
  }
}

}  // namespace
}  // namespace rgbdo
