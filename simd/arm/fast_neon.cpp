// NEON twin of simd/scalar/fast_scalar.cpp: 16 pixels at a time. Blocks without two adjacent
// compass hits (circle 0, 4, 8, 12) on either side hold no corner and are skipped (every arc
// of 9 covers two adjacent compass points); in the others each lane counts its longest run
// of brighter and of darker circle pixels, a corner being a run of 9 (the same booleans as the
// reference's bit test). The score gathers one corner's circle into a vector by lane loads and
// sums its saturated excesses: under half the reference's instructions per corner (5.5 -> ~2.5
// M a frame on the bundled frames, bench/MEASUREMENTS.md#arm-cost-model).
#include <arm_neon.h>

#include <algorithm>
#include <utility>

#include "rgbd_odometry/simd/fast.hpp"

namespace rgbdo::simd {
namespace {

// The sum of the 16 bytes (at most 16 x 255: no overflow in the widening adds).
int sum_u8(uint8x16_t v) {
  const uint64x2_t s = vpaddlq_u32(vpaddlq_u16(vpaddlq_u8(v)));
  return static_cast<int>(vgetq_lane_u64(s, 0) + vgetq_lane_u64(s, 1));
}

// The 16 circle pixels in one vector (in circle order; the sums do not care), by lane loads:
// a corner's circle spans 7 rows, and corners are sparse.
template <int... K>
uint8x16_t load_circle(const std::uint8_t* p, const std::ptrdiff_t* offsets, std::integer_sequence<int, K...>) {
  uint8x16_t v = vdupq_n_u8(0);
  ((v = vld1q_lane_u8(p + offsets[K], v, K)), ...);
  return v;
}

bool all_zero(uint8x16_t v) {
  const uint32x2_t folded = vorr_u32(vget_low_u32(vreinterpretq_u32_u8(v)), vget_high_u32(vreinterpretq_u32_u8(v)));
  return (vget_lane_u32(folded, 0) | vget_lane_u32(folded, 1)) == 0;
}

// The segment test's flags for the 16 pixels at p.
void flag_block(const std::uint8_t* p, const std::ptrdiff_t* offset, uint8x16_t t, std::uint8_t* flags) {
  const uint8x16_t one = vdupq_n_u8(1), two = vdupq_n_u8(2);
  const uint8x16_t c = vld1q_u8(p);
  // Saturated: centre + t above 255 leaves nothing brighter, centre - t below 0 nothing darker.
  const uint8x16_t hi = vqaddq_u8(c, t), lo = vqsubq_u8(c, t);
  // The compass points.
  const uint8x16_t n0 = vld1q_u8(p + offset[0]), n4 = vld1q_u8(p + offset[4]), n8 = vld1q_u8(p + offset[8]),
                   n12 = vld1q_u8(p + offset[12]);
  const uint8x16_t b0 = vcgtq_u8(n0, hi), b4 = vcgtq_u8(n4, hi), b8 = vcgtq_u8(n8, hi), b12 = vcgtq_u8(n12, hi);
  const uint8x16_t d0 = vcltq_u8(n0, lo), d4 = vcltq_u8(n4, lo), d8 = vcltq_u8(n8, lo), d12 = vcltq_u8(n12, lo);
  const uint8x16_t maybe =
      vorrq_u8(vorrq_u8(vorrq_u8(vandq_u8(b0, b4), vandq_u8(b4, b8)), vorrq_u8(vandq_u8(b8, b12), vandq_u8(b12, b0))),
               vorrq_u8(vorrq_u8(vandq_u8(d0, d4), vandq_u8(d4, d8)), vorrq_u8(vandq_u8(d8, d12), vandq_u8(d12, d0))));
  if (all_zero(maybe)) {
    vst1q_u8(flags, vdupq_n_u8(0));
    return;
  }
  // Longest run of brighter (darker) circle pixels, walking the circle one and a half times
  // so that runs across its start are seen whole; a corner has a run of 9. Three registers a
  // side: no 16-plane array to spill (ARMv7 has 16 q registers).
  uint8x16_t run_b = vdupq_n_u8(0), run_d = vdupq_n_u8(0), max_b = run_b, max_d = run_d;
  for (int k = 0; k < 24; ++k) {
    const uint8x16_t x = vld1q_u8(p + offset[k & 15]);
    run_b = vandq_u8(vaddq_u8(run_b, one), vcgtq_u8(x, hi));
    run_d = vandq_u8(vaddq_u8(run_d, one), vcltq_u8(x, lo));
    max_b = vmaxq_u8(max_b, run_b);
    max_d = vmaxq_u8(max_d, run_d);
  }
  const uint8x16_t nine = vdupq_n_u8(9);
  const uint8x16_t bright = vcgeq_u8(max_b, nine), dark = vcgeq_u8(max_d, nine);
  vst1q_u8(flags, vorrq_u8(vandq_u8(bright, one), vandq_u8(dark, two)));
}

}  // namespace

void fast9_row_neon(const std::uint8_t* row, std::ptrdiff_t stride, int n, int threshold, std::uint8_t* flags) {
  std::ptrdiff_t offset[16];
  for (int k = 0; k < 16; ++k) offset[k] = kFastCircle[k][1] * stride + kFastCircle[k][0];
  const uint8x16_t t = vdupq_n_u8(static_cast<std::uint8_t>(threshold > 255 ? 255 : threshold));
  int i = 0;
  for (; i + 16 <= n; i += 16) flag_block(row + i, offset, t, flags + i);
  // The rest as the row's last 16 pixels, some of them flagged again alike: the scalar
  // reference tests one pixel for what a block tests sixteen.
  if (i < n) {
    if (n >= 16) flag_block(row + n - 16, offset, t, flags + n - 16);
    else fast9_row_scalar(row + i, stride, n - i, threshold, flags + i);
  }
}

int fast9_score_neon(const std::uint8_t* p, const std::ptrdiff_t* offsets, int threshold, int flags) {
  const uint8x16_t v = load_circle(p, offsets, std::make_integer_sequence<int, 16>{});
  // Saturated as the row kernel's bounds are: above centre + threshold > 255 nothing is
  // brighter, and below centre - threshold < 0 nothing darker, so clamping changes no excess.
  const int hi = *p + threshold, lo = *p - threshold;
  const int bright = (flags & 1) ? sum_u8(vqsubq_u8(v, vdupq_n_u8(static_cast<std::uint8_t>(std::min(hi, 255))))) : 0;
  const int dark = (flags & 2) ? sum_u8(vqsubq_u8(vdupq_n_u8(static_cast<std::uint8_t>(std::max(lo, 0))), v)) : 0;
  return std::max(bright, dark);
}

}  // namespace rgbdo::simd
