// NEON twin of simd/scalar/fast_scalar.cpp: 16 pixels at a time, the same plan as the AVX2
// twin (simd/x86/fast_avx2.cpp): 16 byte-mask planes of circle comparisons, arcs of 9 by
// doubling runs, blocks without two adjacent compass hits skipped.
#include <arm_neon.h>

#include <initializer_list>

#include "rgbd_odometry/simd/fast.hpp"

namespace rgbdo::simd {
namespace {

uint8x16_t arc_of_9(const uint8x16_t p[16]) {
  uint8x16_t r2[16], r4[16];
  for (int k = 0; k < 16; ++k) r2[k] = vandq_u8(p[k], p[(k + 1) & 15]);
  for (int k = 0; k < 16; ++k) r4[k] = vandq_u8(r2[k], r2[(k + 2) & 15]);
  uint8x16_t any = vdupq_n_u8(0);
  for (int k = 0; k < 16; ++k) any = vorrq_u8(any, vandq_u8(vandq_u8(r4[k], r4[(k + 4) & 15]), p[(k + 8) & 15]));
  return any;
}

bool all_zero(uint8x16_t v) {
  const uint32x2_t folded = vorr_u32(vget_low_u32(vreinterpretq_u32_u8(v)), vget_high_u32(vreinterpretq_u32_u8(v)));
  return (vget_lane_u32(folded, 0) | vget_lane_u32(folded, 1)) == 0;
}

}  // namespace

void fast9_row_neon(const std::uint8_t* row, std::ptrdiff_t stride, int n, int threshold, std::uint8_t* flags) {
  std::ptrdiff_t offset[16];
  for (int k = 0; k < 16; ++k) offset[k] = kFastCircle[k][1] * stride + kFastCircle[k][0];
  const uint8x16_t t = vdupq_n_u8(static_cast<std::uint8_t>(threshold > 255 ? 255 : threshold));
  const uint8x16_t one = vdupq_n_u8(1), two = vdupq_n_u8(2);
  int i = 0;
  for (; i + 16 <= n; i += 16) {
    const std::uint8_t* p = row + i;
    const uint8x16_t c = vld1q_u8(p);
    // Saturated: centre + t above 255 leaves nothing brighter, centre - t below 0 nothing darker.
    const uint8x16_t hi = vqaddq_u8(c, t), lo = vqsubq_u8(c, t);
    uint8x16_t v[16];
    for (const int k : {0, 4, 8, 12}) v[k] = vld1q_u8(p + offset[k]);
    const uint8x16_t b0 = vcgtq_u8(v[0], hi), b4 = vcgtq_u8(v[4], hi), b8 = vcgtq_u8(v[8], hi), b12 = vcgtq_u8(v[12], hi);
    const uint8x16_t d0 = vcltq_u8(v[0], lo), d4 = vcltq_u8(v[4], lo), d8 = vcltq_u8(v[8], lo), d12 = vcltq_u8(v[12], lo);
    const uint8x16_t maybe =
        vorrq_u8(vorrq_u8(vorrq_u8(vandq_u8(b0, b4), vandq_u8(b4, b8)), vorrq_u8(vandq_u8(b8, b12), vandq_u8(b12, b0))),
                 vorrq_u8(vorrq_u8(vandq_u8(d0, d4), vandq_u8(d4, d8)), vorrq_u8(vandq_u8(d8, d12), vandq_u8(d12, d0))));
    if (all_zero(maybe)) {
      vst1q_u8(flags + i, vdupq_n_u8(0));
      continue;
    }
    for (int k = 0; k < 16; ++k)
      if (k % 4 != 0) v[k] = vld1q_u8(p + offset[k]);
    uint8x16_t planes[16];
    for (int k = 0; k < 16; ++k) planes[k] = vcgtq_u8(v[k], hi);
    const uint8x16_t bright = arc_of_9(planes);
    for (int k = 0; k < 16; ++k) planes[k] = vcltq_u8(v[k], lo);
    const uint8x16_t dark = arc_of_9(planes);
    vst1q_u8(flags + i, vorrq_u8(vandq_u8(bright, one), vandq_u8(dark, two)));
  }
  if (i < n) fast9_row_scalar(row + i, stride, n - i, threshold, flags + i);
}

}  // namespace rgbdo::simd
