// NEON twins of the image kernels (simd/scalar/image_scalar.cpp), bit-exact. The pyramid's
// blends are a * 256 - a * w + b * w in 16 bits (VSHLL, VMLSL, VMLAL: exact, as the result
// is below 2^16) rounded by VRSHRN; the horizontal pass gathers its 16 source bytes per
// group of eight outputs with VTBL.
#include <arm_neon.h>

#include <cstring>

#include "disc_masks.hpp"
#include "neon_compare.hpp"
#include "rgbd_odometry/simd/image.hpp"

namespace rgbdo::simd {
namespace {

inline uint8x8_t blend8(uint8x8_t a, uint8x8_t b, uint8x8_t w) {
  uint16x8_t acc = vshll_n_u8(a, 8);
  acc = vmlsl_u8(acc, a, w);
  acc = vmlal_u8(acc, b, w);
  return vrshrn_n_u16(acc, 8);
}

// An order-preserving integer key of a float (IEEE order; -0 and +0 one key; a NaN's key
// lies beyond both infinities), so the range test needs no float compare: NEON's flushes
// denormals to zero, which would differ from the scalar reference.
inline std::int32_t float_key(float f) {
  std::int32_t x;
  std::memcpy(&x, &f, sizeof x);
  if (x == INT32_MIN) x = 0;
  return x ^ ((x >> 31) & 0x7FFFFFFF);
}

inline int32x4_t float_keys(int32x4_t x) {
  x = vbicq_s32(x, vreinterpretq_s32_u32(vceqq_s32(x, vdupq_n_s32(INT32_MIN))));
  return veorq_s32(x, vandq_s32(vshrq_n_s32(x, 31), vdupq_n_s32(0x7FFFFFFF)));
}

}  // namespace

RGBDO_BLEND_ROWS(blend_rows_neon) {
  if (w == 0 || w == 256) {  // a copy (w fits no byte at 256)
    std::memcpy(out, w == 0 ? r0 : r1, static_cast<std::size_t>(n));
    return;
  }
  const uint8x8_t wv = vdup_n_u8(static_cast<std::uint8_t>(w));
  int i = 0;
  for (; i + 16 <= n; i += 16) {
    const uint8x16_t a = vld1q_u8(r0 + i), b = vld1q_u8(r1 + i);
    vst1q_u8(out + i, vcombine_u8(blend8(vget_low_u8(a), vget_low_u8(b), wv), blend8(vget_high_u8(a), vget_high_u8(b), wv)));
  }
  blend_rows_scalar(r0 + i, r1 + i, n - i, w, out + i);
}

RGBDO_RESAMPLE_ROW(resample_row_neon) {
  const uint8x8_t one = vdup_n_u8(1);
  int g = 0;
  for (; (g + 1) * 8 <= n; ++g) {
    const ResampleGroup& group = groups[g];
    const uint8x16_t s = vld1q_u8(src + group.base);
    const uint8x8x2_t table = {{vget_low_u8(s), vget_high_u8(s)}};
    const uint8x8_t index = vld1_u8(group.index);
    const uint8x8_t a = vtbl2_u8(table, index), b = vtbl2_u8(table, vadd_u8(index, one));
    vst1_u8(out + g * 8, blend8(a, b, vld1_u8(group.weight)));
  }
  resample_row_scalar(src, groups + g, n - g * 8, out + g * 8);
}

namespace {

// Eight box sums, columns i..i+7.
void box5_block8(const std::uint8_t* centre, std::ptrdiff_t stride, int i, std::uint16_t* out) {
  // Column sums of columns i-2..i+5 (left) and i+2..i+9 (right): 8-byte loads reach no
  // further than the 2 pixels the caller keeps.
  const std::uint8_t* p = centre + i - 2 - 2 * stride;
  uint16x8_t left = vaddl_u8(vld1_u8(p), vld1_u8(p + stride));
  uint16x8_t right = vaddl_u8(vld1_u8(p + 4), vld1_u8(p + 4 + stride));
  for (int dy = 2; dy < 5; ++dy) {
    left = vaddw_u8(left, vld1_u8(p + dy * stride));
    right = vaddw_u8(right, vld1_u8(p + 4 + dy * stride));
  }
  // Columns i+6..i+9 moved to lanes 0..3: with `left`, columns i-2..i+9 in order.
  const uint16x8_t next = vextq_u16(right, right, 4);
  uint16x8_t sum = left;
  sum = vaddq_u16(sum, vextq_u16(left, next, 1));
  sum = vaddq_u16(sum, vextq_u16(left, next, 2));
  sum = vaddq_u16(sum, vextq_u16(left, next, 3));
  sum = vaddq_u16(sum, vextq_u16(left, next, 4));
  vst1q_u16(out + i, sum);
}

}  // namespace

RGBDO_BOX5_ROW(box5_row_neon) {
  if (n < 8) {
    box5_row_scalar(centre, stride, n, out);
    return;
  }
  for (int i = 0; i + 8 <= n; i += 8) box5_block8(centre, stride, i, out);
  // The last columns as one more block ending at the row's end, overlapping the one before
  // (the same sums written again): the scalar loop cost 0.5 M ARM instructions a frame.
  if (n % 8 != 0) box5_block8(centre, stride, n - 8, out);
}

RGBDO_SURFACE_MEAN5(surface_mean5_neon) {
  // Per row two overlapping loads: columns 0-3 and 1-4. The first is summed lane by lane, the
  // second's last lane is column 4's sum: the reference's order, so the sum is bit-exact.
  // Minimum and maximum take both loads (an overlap changes neither).
  for (int k = 0; k < n; ++k) {
    const float* c = depth + centre[k];
    float32x4_t lanes = vdupq_n_f32(0), column4 = vdupq_n_f32(0);
    float32x4_t lo = vdupq_n_f32(c[0]), hi = lo;
    for (std::ptrdiff_t dv = -2; dv <= 2; ++dv) {
      const float* row = c + dv * stride - 2;
      const float32x4_t a = vld1q_f32(row), b = vld1q_f32(row + 1);
      lanes = vaddq_f32(lanes, a);
      column4 = vaddq_f32(column4, b);
      lo = vminq_f32(lo, vminq_f32(a, b));
      hi = vmaxq_f32(hi, vmaxq_f32(a, b));
    }
    const float32x2_t pairs = vpadd_f32(vget_low_f32(lanes), vget_high_f32(lanes));  // (c0 + c1, c2 + c3)
    const float sum = (vget_lane_f32(pairs, 0) + vget_lane_f32(pairs, 1)) + vgetq_lane_f32(column4, 3);
    float32x2_t lo2 = vpmin_f32(vget_low_f32(lo), vget_high_f32(lo));
    lo2 = vpmin_f32(lo2, lo2);
    float32x2_t hi2 = vpmax_f32(vget_low_f32(hi), vget_high_f32(hi));
    hi2 = vpmax_f32(hi2, hi2);
    // The verdict by NEON compares, not VFP's (neon_compare.hpp); depths are 0 or normal floats.
    const float32x4_t low = vdupq_lane_f32(lo2, 0);
    const float32x4_t span = vsubq_f32(vdupq_lane_f32(hi2, 0), low);
    const uint32x4_t one_surface =
        vandq_u32(neon::greater(low, vdupq_n_f32(0)), neon::greater_equal(vdupq_n_f32(spread * c[0]), span));
    mean[k] = vgetq_lane_u32(one_surface, 0) != 0 ? sum * kSurfaceMeanScale : c[0];
  }
}

RGBDO_DEPTH_IN_RANGE_ROW(depth_in_range_row_neon) {
  const std::int32_t lo_key = float_key(lo), hi_key = float_key(hi);
  const int32x4_t lov = vdupq_n_s32(lo_key), hiv = vdupq_n_s32(hi_key);
  int i = 0;
  for (; i + 8 <= n; i += 8) {
    // Loaded as floats, reinterpreted: no float operation touches them.
    const int32x4_t a = float_keys(vreinterpretq_s32_f32(vld1q_f32(depth + i)));
    const int32x4_t b = float_keys(vreinterpretq_s32_f32(vld1q_f32(depth + i + 4)));
    const uint32x4_t in_a = vandq_u32(vcgeq_s32(a, lov), vcleq_s32(a, hiv));
    const uint32x4_t in_b = vandq_u32(vcgeq_s32(b, lov), vcleq_s32(b, hiv));
    vst1_u8(out + i, vmovn_u16(vcombine_u16(vmovn_u32(in_a), vmovn_u32(in_b))));
  }
  depth_in_range_row_scalar(depth + i, n - i, lo, hi, out + i);  // VFP keeps denormals (Linux)
}

// m10 = sum (dx + 16) I - 16 sum I: unsigned products for VMULL.
RGBDO_COLOUR_TO_GRAY_ROW(colour_to_gray_row_neon) {
  const std::uint16_t first = red_first ? kGrayRed : kGrayBlue, third = red_first ? kGrayBlue : kGrayRed;
  int i = 0;
  for (; i + 8 <= n; i += 8) {
    const uint8x8x3_t px = vld3_u8(pixels + 3 * i);  // de-interleaved channels
    const uint16x8_t c0 = vmovl_u8(px.val[0]), c1 = vmovl_u8(px.val[1]), c2 = vmovl_u8(px.val[2]);
    uint32x4_t lo = vmull_n_u16(vget_low_u16(c0), first), hi = vmull_n_u16(vget_high_u16(c0), first);
    lo = vmlal_n_u16(lo, vget_low_u16(c1), static_cast<std::uint16_t>(kGrayGreen));
    hi = vmlal_n_u16(hi, vget_high_u16(c1), static_cast<std::uint16_t>(kGrayGreen));
    lo = vmlal_n_u16(lo, vget_low_u16(c2), third);
    hi = vmlal_n_u16(hi, vget_high_u16(c2), third);
    // + 2^14, >> 15 (VRSHRN): at most 255, so the narrowing is exact.
    vst1_u8(out + i, vmovn_u16(vcombine_u16(vrshrn_n_u32(lo, 15), vrshrn_n_u32(hi, 15))));
  }
  colour_to_gray_row_scalar(pixels + 3 * i, n - i, red_first, out + i);
}

RGBDO_DEPTH_TO_METRES_ROW(depth_to_metres_row_neon) {
  // Readings up to 65535 times a scale of 1e-6..1e3 (the configuration's range): no product
  // is a denormal, which NEON alone would flush.
  const float32x4_t scale = vdupq_n_f32(metres_per_unit);
  int i = 0;
  for (; i + 8 <= n; i += 8) {
    const uint16x8_t r = vld1q_u16(raw + i);
    vst1q_f32(out + i, vmulq_f32(vcvtq_f32_u32(vmovl_u16(vget_low_u16(r))), scale));
    vst1q_f32(out + i + 4, vmulq_f32(vcvtq_f32_u32(vmovl_u16(vget_high_u16(r))), scale));
  }
  depth_to_metres_row_scalar(raw + i, n - i, metres_per_unit, out + i);
}

RGBDO_DISC_MOMENTS(disc_moments_neon) {
  static const std::uint8_t weights[32] = {0,  1,  2,  3,  4,  5,  6,  7,  8,  9,  10, 11, 12, 13, 14, 15,
                                           16, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29, 30, 31};
  const uint8x8_t w0 = vld1_u8(weights), w1 = vld1_u8(weights + 8), w2 = vld1_u8(weights + 16), w3 = vld1_u8(weights + 24);
  uint32x4_t weighted = vdupq_n_u32(0), total = vdupq_n_u32(0);
  int32x4_t by_row = vdupq_n_s32(0);
  for (int dy = -kDiscRadius; dy <= kDiscRadius; ++dy) {
    const std::uint8_t* p = centre + dy * stride - 16;
    const std::uint8_t* m = kDiscMasks.row[dy + kDiscRadius];
    const uint8x16_t a = vandq_u8(vld1q_u8(p), vld1q_u8(m)), b = vandq_u8(vld1q_u8(p + 16), vld1q_u8(m + 16));
    // (dx + 16) * I: at most 31 * 255, summed in pairs into 32 bits.
    weighted = vpadalq_u16(weighted, vmull_u8(vget_low_u8(a), w0));
    weighted = vpadalq_u16(weighted, vmull_u8(vget_high_u8(a), w1));
    weighted = vpadalq_u16(weighted, vmull_u8(vget_low_u8(b), w2));
    weighted = vpadalq_u16(weighted, vmull_u8(vget_high_u8(b), w3));
    const uint16x8_t row_sum = vaddq_u16(vpaddlq_u8(a), vpaddlq_u8(b));  // 8 lanes of <= 4 * 255
    total = vpadalq_u16(total, row_sum);
    const int16x8_t rs = vreinterpretq_s16_u16(row_sum);
    by_row = vmlal_n_s16(by_row, vget_low_s16(rs), static_cast<std::int16_t>(dy));
    by_row = vmlal_n_s16(by_row, vget_high_s16(rs), static_cast<std::int16_t>(dy));
  }
  const auto sum_u32 = [](uint32x4_t v) {
    const uint64x2_t p = vpaddlq_u32(v);
    return static_cast<std::uint32_t>(vgetq_lane_u64(p, 0) + vgetq_lane_u64(p, 1));
  };
  const auto sum_s32 = [](int32x4_t v) {
    const int64x2_t p = vpaddlq_s32(v);
    return static_cast<std::int32_t>(vgetq_lane_s64(p, 0) + vgetq_lane_s64(p, 1));
  };
  *m10 = static_cast<std::int32_t>(sum_u32(weighted)) - 16 * static_cast<std::int32_t>(sum_u32(total));
  *m01 = sum_s32(by_row);
}

}  // namespace rgbdo::simd
