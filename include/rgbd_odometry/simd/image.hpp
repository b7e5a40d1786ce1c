#pragma once
// Kernel interfaces for the image work of our feature extractor (pipeline/grid_orb.hpp) and
// of the feature mask (pipeline/mask.hpp): the pyramid's two resampling passes, the 5x5 box
// sums the descriptor compares, and the depth range test. Every result is an exact integer
// (or a boolean of one comparison), so every twin is bit-exact against its scalar reference
// in simd/scalar/image_scalar.cpp.
#include <cstddef>
#include <cstdint>

namespace rgbdo::simd {

// Vertical pass: out[i] = (r0[i] * (256 - w) + r1[i] * w + 128) >> 8, w in [0, 256].
#define RGBDO_BLEND_ROWS(name) \
  void name(const std::uint8_t* r0, const std::uint8_t* r1, int n, unsigned w, std::uint8_t* out)

// Horizontal pass, eight outputs per group: for output k of group g (k < 8, g * 8 + k < n),
//   a = src[base + index[k]], b = src[base + index[k] + 1],
//   out[g * 8 + k] = (a * (256 - weight[k]) + b * weight[k] + 128) >> 8.
// index[k] + 1 <= 15 and the caller keeps src readable up to base + 16 of every group, so a
// twin may load the 16 bytes from base at once (downscaling by at most 2 always fits).
struct ResampleGroup {
  std::int32_t base;
  std::uint8_t index[8];
  std::uint8_t weight[8];  // of the right-hand pixel, in 1/256
};
#define RGBDO_RESAMPLE_ROW(name) \
  void name(const std::uint8_t* src, const ResampleGroup* groups, int n, std::uint8_t* out)

// 5x5 box sums: out[i] = sum over dy, dx in [-2, 2] of centre[i + dy * stride + dx], for
// i in [0, n). The caller keeps 2 pixels of image on every side of the run.
#define RGBDO_BOX5_ROW(name) \
  void name(const std::uint8_t* centre, std::ptrdiff_t stride, int n, std::uint16_t* out)

// Depth range test: out[i] = 255 when lo <= depth[i] <= hi (cv::inRange's rule), else 0
// (NaN: 0).
#define RGBDO_DEPTH_IN_RANGE_ROW(name) \
  void name(const float* depth, int n, float lo, float hi, std::uint8_t* out)

// The depth alignment's samples averaged on their surfaces: for each of n samples, centre[k] the
// index of its pixel in an image of row stride `stride` floats (the caller keeps 2 pixels of
// image on every side, and every depth 0 or a normal float), the 5x5 depths around it. Where all 25 are
// positive and the largest exceeds the smallest by at most spread * the centre's depth, mean[k]
// is their sum times 1/25, summed in one order every set keeps: four column lanes (the window's
// columns 0-3) and column 4, each over rows -2..2 in turn, then ((c0 + c1) + (c2 + c3)) + c4.
// Elsewhere (a hole, an edge) mean[k] is the centre's own depth.
inline constexpr float kSurfaceMeanScale = 1.0f / 25.0f;
#define RGBDO_SURFACE_MEAN5(name) \
  void name(const float* depth, std::ptrdiff_t stride, const std::int32_t* centre, int n, float spread, float* mean)

// Colour to intensity as OpenCV's cvtColor(..., COLOR_BGR2GRAY / COLOR_RGB2GRAY) computes it
// for 8-bit images (OpenCV 4's fixed point, 15 fraction bits: 0.299 R + 0.587 G + 0.114 B,
// checked against cvtColor by test_image_kernels), so that
// replays and live frames keep OpenCV's grey values; pixels are 3 bytes, blue first unless
// red_first.
inline constexpr std::uint32_t kGrayRed = 9798, kGrayGreen = 19235, kGrayBlue = 3735;  // sum 2^15
#define RGBDO_COLOUR_TO_GRAY_ROW(name) \
  void name(const std::uint8_t* pixels, int n, bool red_first, std::uint8_t* out)

// Depth readings to metres: out[i] = float(raw[i]) * metres_per_unit, one float product (as
// cv::Mat::convertTo to CV_32F with that scale computes it).
#define RGBDO_DEPTH_TO_METRES_ROW(name) \
  void name(const std::uint16_t* raw, int n, float metres_per_unit, float* out)

// Intensity-centroid moments (Rosin; ORB's orientation) over the disc of radius 15:
//   m10 = sum of dx * I(dx, dy), m01 = sum of dy * I(dx, dy), |dx| <= kDiscHalfWidth15[|dy|].
// The caller keeps 16 columns left of the centre, 15 right and 15 rows above and below.
inline constexpr int kDiscRadius = 15;
inline constexpr int kDiscHalfWidth15[kDiscRadius + 1] = {15, 14, 14, 14, 14, 14, 13, 13, 12, 12, 11, 10, 9, 7, 5, 0};
#define RGBDO_DISC_MOMENTS(name) \
  void name(const std::uint8_t* centre, std::ptrdiff_t stride, std::int32_t* m10, std::int32_t* m01)

RGBDO_BLEND_ROWS(blend_rows_scalar);  // the references: simd/scalar/image_scalar.cpp
RGBDO_RESAMPLE_ROW(resample_row_scalar);
RGBDO_BOX5_ROW(box5_row_scalar);
RGBDO_DEPTH_IN_RANGE_ROW(depth_in_range_row_scalar);
RGBDO_DISC_MOMENTS(disc_moments_scalar);
RGBDO_COLOUR_TO_GRAY_ROW(colour_to_gray_row_scalar);  // also the x86 sets' (not the target's hot path)
RGBDO_DEPTH_TO_METRES_ROW(depth_to_metres_row_scalar);
RGBDO_SURFACE_MEAN5(surface_mean5_scalar);  // also the x86 sets' (not the target's hot path)

RGBDO_BLEND_ROWS(blend_rows_sse41);  // simd/x86/image_sse41.cpp (the sse42 and avx2 sets)
RGBDO_RESAMPLE_ROW(resample_row_sse41);
RGBDO_BOX5_ROW(box5_row_sse41);
RGBDO_DEPTH_IN_RANGE_ROW(depth_in_range_row_sse41);
RGBDO_DISC_MOMENTS(disc_moments_sse41);

RGBDO_BLEND_ROWS(blend_rows_neon);  // simd/arm/image_neon.cpp
RGBDO_RESAMPLE_ROW(resample_row_neon);
RGBDO_BOX5_ROW(box5_row_neon);
RGBDO_DEPTH_IN_RANGE_ROW(depth_in_range_row_neon);
RGBDO_DISC_MOMENTS(disc_moments_neon);
RGBDO_COLOUR_TO_GRAY_ROW(colour_to_gray_row_neon);
RGBDO_DEPTH_TO_METRES_ROW(depth_to_metres_row_neon);
RGBDO_SURFACE_MEAN5(surface_mean5_neon);

}  // namespace rgbdo::simd
