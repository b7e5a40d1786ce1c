// Reference FAST-9 segment test and score (rgbd_odometry/simd/fast.hpp): per pixel, the 16
// circle comparisons as bit masks and an arc-of-9 test by doubling runs of ones; the score as
// two sums over the circle.
#include "rgbd_odometry/simd/fast.hpp"

#include <algorithm>

namespace rgbdo::simd {
namespace {

// Whether the 16 circle bits hold 9 contiguous ones (the circle wraps round).
bool has_arc_of_9(std::uint32_t bits16) {
  std::uint32_t x = bits16 | (bits16 << 16);
  x &= x >> 1;  // runs of 2
  x &= x >> 2;  // runs of 4
  x &= x >> 4;  // runs of 8
  x &= x >> 1;  // runs of 9
  return (x & 0xFFFFu) != 0;
}

}  // namespace

void fast9_row_scalar(const std::uint8_t* row, std::ptrdiff_t stride, int n, int threshold, std::uint8_t* flags) {
  std::ptrdiff_t offset[16];
  for (int k = 0; k < 16; ++k) offset[k] = kFastCircle[k][1] * stride + kFastCircle[k][0];
  for (int i = 0; i < n; ++i) {
    const std::uint8_t* p = row + i;
    const int hi = *p + threshold, lo = *p - threshold;
    std::uint32_t bright = 0, dark = 0;
    for (int k = 0; k < 16; ++k) {
      const int v = p[offset[k]];
      bright |= static_cast<std::uint32_t>(v > hi) << k;
      dark |= static_cast<std::uint32_t>(v < lo) << k;
    }
    flags[i] = static_cast<std::uint8_t>((has_arc_of_9(bright) ? 1 : 0) | (has_arc_of_9(dark) ? 2 : 0));
  }
}

int fast9_score_scalar(const std::uint8_t* p, const std::ptrdiff_t* offsets, int threshold, int flags) {
  const int hi = *p + threshold, lo = *p - threshold;
  int excess_bright = 0, excess_dark = 0;
  for (int k = 0; k < 16; ++k) {
    const int v = p[offsets[k]];
    excess_bright += std::max(v - hi, 0);
    excess_dark += std::max(lo - v, 0);
  }
  return std::max((flags & 1) ? excess_bright : 0, (flags & 2) ? excess_dark : 0);
}

}  // namespace rgbdo::simd
