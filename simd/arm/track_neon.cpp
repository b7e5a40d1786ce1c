// NEON twins of the sub-pixel tracker's kernels (rgbd_odometry/simd/track.hpp): a patch row is
// one 8-lane vector, the bilinear sum four widening multiply-accumulates per half, the patch
// sums widening multiply-accumulates reduced once at the end. Integer throughout, so every
// result is bit-exact against simd/scalar/track_scalar.cpp.
#include <arm_neon.h>

#include "rgbd_odometry/simd/track.hpp"

namespace rgbdo::simd {

void track_sample8_neon(const std::uint8_t* top_left, std::ptrdiff_t stride, int rows, const std::int32_t* w,
                        std::int16_t* out) {
  constexpr int shift = kTrackWeightBits - kTrackValueBits;
  // Weights are at most 2^14: they fit the 16-bit lanes of the widening multiplies.
  const auto w00 = static_cast<std::uint16_t>(w[0]), w01 = static_cast<std::uint16_t>(w[1]),
             w10 = static_cast<std::uint16_t>(w[2]), w11 = static_cast<std::uint16_t>(w[3]);
  uint16x8_t p0 = vmovl_u8(vld1_u8(top_left)), p1 = vmovl_u8(vld1_u8(top_left + 1));
  for (int r = 0; r < rows; ++r) {
    const std::uint8_t* q = top_left + (r + 1) * stride;
    const uint16x8_t q0 = vmovl_u8(vld1_u8(q)), q1 = vmovl_u8(vld1_u8(q + 1));
    uint32x4_t lo = vmull_n_u16(vget_low_u16(p0), w00);
    lo = vmlal_n_u16(lo, vget_low_u16(p1), w01);
    lo = vmlal_n_u16(lo, vget_low_u16(q0), w10);
    lo = vmlal_n_u16(lo, vget_low_u16(q1), w11);
    uint32x4_t hi = vmull_n_u16(vget_high_u16(p0), w00);
    hi = vmlal_n_u16(hi, vget_high_u16(p1), w01);
    hi = vmlal_n_u16(hi, vget_high_u16(q0), w10);
    hi = vmlal_n_u16(hi, vget_high_u16(q1), w11);
    // Rounding narrowing shift: (v + 2^(shift-1)) >> shift, as the reference.
    const uint16x8_t v = vcombine_u16(vrshrn_n_u32(lo, shift), vrshrn_n_u32(hi, shift));
    vst1q_s16(out + r * 8, vreinterpretq_s16_u16(v));
    p0 = q0;
    p1 = q1;
  }
}

void track_sums8x8_neon(const std::int16_t* sampled, const std::int16_t* templ, const std::int16_t* gx,
                        const std::int16_t* gy, std::int32_t* sums) {
  int32x4_t sx = vdupq_n_s32(0), sy = vdupq_n_s32(0), sd = vdupq_n_s32(0);
  for (int r = 0; r < 8; ++r) {
    const int16x8_t d = vsubq_s16(vld1q_s16(sampled + r * 8), vld1q_s16(templ + r * 8));
    const int16x8_t x = vld1q_s16(gx + r * 8), y = vld1q_s16(gy + r * 8);
    sx = vmlal_s16(sx, vget_low_s16(d), vget_low_s16(x));
    sx = vmlal_s16(sx, vget_high_s16(d), vget_high_s16(x));
    sy = vmlal_s16(sy, vget_low_s16(d), vget_low_s16(y));
    sy = vmlal_s16(sy, vget_high_s16(d), vget_high_s16(y));
    sd = vmlal_s16(sd, vget_low_s16(d), vget_low_s16(d));
    sd = vmlal_s16(sd, vget_high_s16(d), vget_high_s16(d));
  }
  const auto total = [](int32x4_t v) {
    const int32x2_t s = vadd_s32(vget_low_s32(v), vget_high_s32(v));
    return vget_lane_s32(vpadd_s32(s, s), 0);
  };
  sums[0] = total(sx);
  sums[1] = total(sy);
  sums[2] = total(sd);
}

}  // namespace rgbdo::simd
