#pragma once
// Kernels of the sub-pixel tracker (pipeline/track.cpp): Lucas-Kanade on patches 8 pixels
// wide, in fixed point, so that every twin is bit-exact against simd/scalar/track_scalar.cpp.
#include <cstddef>
#include <cstdint>

namespace rgbdo::simd {

// Bilinear weights are non-negative kTrackWeightBits-bit fractions (w00 + w01 + w10 + w11 =
// 1 << 14, as OpenCV's calcOpticalFlowPyrLK); sampled values keep kTrackValueBits fractional bits of a
// grey level, so that the sums below stay within 32 bits: values up to 2040, differences of
// two within +-2040, a product of two differences under 2^22, 64 of them under 2^28.
inline constexpr int kTrackWeightBits = 14;
inline constexpr int kTrackValueBits = 3;

// `rows` rows of 8 values sampled between pixels: row r, column i is
//   (w[0] p[i] + w[1] p[i+1] + w[2] q[i] + w[3] q[i+1] + 2^10) >> 11,
// p = top_left + r * stride, q = p + stride. Reads rows + 1 image rows of 9 bytes each.
#define RGBDO_TRACK_SAMPLE(name) \
  void name(const std::uint8_t* top_left, std::ptrdiff_t stride, int rows, const std::int32_t* w, std::int16_t* out)
RGBDO_TRACK_SAMPLE(track_sample8_scalar);  // simd/scalar/track_scalar.cpp, the reference
RGBDO_TRACK_SAMPLE(track_sample8_neon);    // simd/arm/track_neon.cpp

// Over an 8x8 patch (64 values, row after row): with d = sampled - templ,
// sums[0] = sum d gx, sums[1] = sum d gy, sums[2] = sum d^2, in 32-bit integers.
#define RGBDO_TRACK_SUMS(name)                                                                           \
  void name(const std::int16_t* sampled, const std::int16_t* templ, const std::int16_t* gx, const std::int16_t* gy, \
            std::int32_t* sums)
RGBDO_TRACK_SUMS(track_sums8x8_scalar);  // simd/scalar/track_scalar.cpp, the reference
RGBDO_TRACK_SUMS(track_sums8x8_neon);    // simd/arm/track_neon.cpp

}  // namespace rgbdo::simd
