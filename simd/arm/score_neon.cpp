// NEON twin of simd/scalar/score_scalar.cpp: its 8 lanes as two q registers of 4, the same
// operations in the same order (no fused multiply-add), the same reduction tree.
#include <arm_neon.h>

#include "neon_compare.hpp"
#include "rgbd_odometry/simd/score.hpp"

namespace rgbdo::simd {

void score_rigid_neon(const RigidScoreInput& in, int& count, float& cost) {
  const float* r = in.r;
  const float32x4_t thr = vdupq_n_f32(in.threshold_sq);
  float32x4_t lane_cost[2] = {vdupq_n_f32(0), vdupq_n_f32(0)};
  uint32x4_t lane_count[2] = {vdupq_n_u32(0), vdupq_n_u32(0)};
  const auto row = [&](int i, float32x4_t cx, float32x4_t cy, float32x4_t cz) {
    return vaddq_f32(vaddq_f32(vaddq_f32(vmulq_n_f32(cx, r[3 * i]), vmulq_n_f32(cy, r[3 * i + 1])), vmulq_n_f32(cz, r[3 * i + 2])),
                     vdupq_n_f32(in.t[i]));
  };
  const auto step = [&](int h, float32x4_t px, float32x4_t py, float32x4_t pz, float32x4_t cx, float32x4_t cy,
                        float32x4_t cz, uint32x4_t valid) {
    const float32x4_t ex = vsubq_f32(px, row(0, cx, cy, cz));
    const float32x4_t ey = vsubq_f32(py, row(1, cx, cy, cz));
    const float32x4_t ez = vsubq_f32(pz, row(2, cx, cy, cz));
    const float32x4_t e = vaddq_f32(vaddq_f32(vmulq_f32(ex, ex), vmulq_f32(ey, ey)), vmulq_f32(ez, ez));
    const uint32x4_t inside = vandq_u32(neon::less(e, thr), valid);
    const float32x4_t term = vreinterpretq_f32_u32(vandq_u32(vreinterpretq_u32_f32(vbslq_f32(inside, e, thr)), valid));
    lane_cost[h] = vaddq_f32(lane_cost[h], term);
    lane_count[h] = vsubq_u32(lane_count[h], inside);  // true lanes are all ones (-1)
  };
  const uint32x4_t all = vdupq_n_u32(0xFFFFFFFFu);
  int k = 0;
  for (; k + 8 <= in.n; k += 8)
    for (int h = 0; h < 2; ++h) {
      const int o = k + 4 * h;
      step(h, vld1q_f32(in.px + o), vld1q_f32(in.py + o), vld1q_f32(in.pz + o), vld1q_f32(in.cx + o),
           vld1q_f32(in.cy + o), vld1q_f32(in.cz + o), all);
    }
  if (k < in.n) {
    float buf[6][8] = {};
    std::uint32_t mask[8] = {};
    for (int l = 0; k + l < in.n; ++l) {
      buf[0][l] = in.px[k + l], buf[1][l] = in.py[k + l], buf[2][l] = in.pz[k + l];
      buf[3][l] = in.cx[k + l], buf[4][l] = in.cy[k + l], buf[5][l] = in.cz[k + l];
      mask[l] = 0xFFFFFFFFu;
    }
    for (int h = 0; h < 2; ++h)
      step(h, vld1q_f32(buf[0] + 4 * h), vld1q_f32(buf[1] + 4 * h), vld1q_f32(buf[2] + 4 * h), vld1q_f32(buf[3] + 4 * h),
           vld1q_f32(buf[4] + 4 * h), vld1q_f32(buf[5] + 4 * h), vld1q_u32(mask + 4 * h));
  }
  float c[8];
  std::uint32_t n[8];
  vst1q_f32(c, lane_cost[0]);
  vst1q_f32(c + 4, lane_cost[1]);
  vst1q_u32(n, lane_count[0]);
  vst1q_u32(n + 4, lane_count[1]);
  for (int l = 0; l < 4; ++l) c[l] = c[l] + c[l + 4];
  for (int l = 0; l < 2; ++l) c[l] = c[l] + c[l + 2];
  cost = c[0] + c[1];
  count = 0;
  for (std::uint32_t x : n) count += static_cast<int>(x);
}

}  // namespace rgbdo::simd
