// NEON twin of simd/scalar/associate_scalar.cpp: four points a step, the reference's
// operations in its order. VMLA on ARMv7 NEON rounds the product before it adds (it is not
// fused), so a + b c by it is the reference's. NEON has no divide, and an estimate refined by
// Newton steps is not IEEE's quotient: the two divisions (1 / z, the weight) are done lane by
// lane on VFP, whose registers the NEON ones share. The previous grid's normals and points are
// gathered and the associations written lane by lane by single structure loads and stores
// (VLD3 / VST4 to one lane); the compares are neon_compare.hpp's. NEON flushes denormal floats
// to zero, which no point, normal or weight of a depth map in metres comes near.
#include <arm_neon.h>

#include "neon_compare.hpp"
#include "rgbd_odometry/simd/associate.hpp"

namespace rgbdo::simd {
namespace {

// ((a x + b y) + c z), as the reference rounds it.
inline float32x4_t dot3(float a, float32x4_t x, float b, float32x4_t y, float c, float32x4_t z) {
  return vmlaq_n_f32(vmlaq_n_f32(vmulq_n_f32(x, a), y, b), z, c);
}

inline bool any(uint32x4_t m) {
  const uint32x2_t h = vorr_u32(vget_low_u32(m), vget_high_u32(m));
  return vget_lane_u32(vpmax_u32(h, h), 0) != 0;
}

// 1 / d lane by lane, IEEE's quotient.
inline float32x4_t reciprocal(float32x4_t d) {
  float32x4_t r = d;
  r = vsetq_lane_f32(1.0f / vgetq_lane_f32(d, 0), r, 0);
  r = vsetq_lane_f32(1.0f / vgetq_lane_f32(d, 1), r, 1);
  r = vsetq_lane_f32(1.0f / vgetq_lane_f32(d, 2), r, 2);
  r = vsetq_lane_f32(1.0f / vgetq_lane_f32(d, 3), r, 3);
  return r;
}

// Lane L's normal and point of the previous grid at sample k.
template <int L>
inline void gather(const AssociateInput& in, int32x4_t k, float32x4x3_t& normal, float32x4x3_t& point) {
  const int at = 3 * vgetq_lane_s32(k, L);
  normal = vld3q_lane_f32(in.prev_normal + at, normal, L);
  point = vld3q_lane_f32(in.prev_point + at, point, L);
}

// Lane L's association, written where `out` points.
template <int L>
inline void write(const float32x4x4_t& head, const float32x4x4_t& tail, int32x4_t k, std::int32_t curr_index,
                  Association* out) {
  vst4q_lane_f32(&out->r, head, L);      // r, w, j[0], j[1]
  vst4q_lane_f32(&out->j[2], tail, L);   // j[2] .. j[5]
  out->curr_index = curr_index;
  out->prev_index = vgetq_lane_s32(k, L);
}

}  // namespace

int associate_neon(const AssociateInput& in, Association* out) {
  const float* R = in.r;
  const float32x4_t zero = vdupq_n_f32(0.0f), one = vdupq_n_f32(1.0f);
  const float32x4_t cols = vdupq_n_f32(static_cast<float>(in.cols)), rows = vdupq_n_f32(static_cast<float>(in.rows));
  const float32x4_t max_d2 = vdupq_n_f32(in.max_d2), floor2 = vdupq_n_f32(in.floor2);
  const float32x4_t tx = vdupq_n_f32(in.t[0]), ty = vdupq_n_f32(in.t[1]), tz = vdupq_n_f32(in.t[2]);
  const float32x4_t cx = vdupq_n_f32(in.cx), cy = vdupq_n_f32(in.cy);
  int count = 0;
  for (int i0 = 0; i0 < in.n; i0 += 4) {
    float32x4_t px, py, pz;
    // Four points by one de-interleaving load where every point it reads lies before the
    // row's last one taken; the last group through a buffer, missing lanes without a point.
    if (in.step == 1 && i0 + 4 <= in.n) {
      const float32x4x3_t v = vld3q_f32(in.curr + 3 * i0);
      px = v.val[0], py = v.val[1], pz = v.val[2];
    } else if (in.step == 2 && i0 + 4 < in.n) {
      const float32x4x3_t a = vld3q_f32(in.curr + 6 * i0), b = vld3q_f32(in.curr + 6 * i0 + 12);
      px = vuzpq_f32(a.val[0], b.val[0]).val[0];
      py = vuzpq_f32(a.val[1], b.val[1]).val[0];
      pz = vuzpq_f32(a.val[2], b.val[2]).val[0];
    } else {
      float x[4] = {}, y[4] = {}, z[4] = {};
      for (int l = 0; l < 4 && i0 + l < in.n; ++l) {
        const float* p = in.curr + 3 * in.step * (i0 + l);
        x[l] = p[0], y[l] = p[1], z[l] = p[2];
      }
      px = vld1q_f32(x), py = vld1q_f32(y), pz = vld1q_f32(z);
    }
    const float32x4_t qz = vaddq_f32(dot3(R[6], px, R[7], py, R[8], pz), tz);
    uint32x4_t valid = vbicq_u32(neon::greater(qz, zero), vceqq_f32(pz, zero));
    if (!any(valid)) continue;
    const float32x4_t qx = vaddq_f32(dot3(R[0], px, R[1], py, R[2], pz), tx);
    const float32x4_t qy = vaddq_f32(dot3(R[3], px, R[4], py, R[5], pz), ty);
    const float32x4_t iz = reciprocal(vbslq_f32(valid, qz, one));  // 1 / 1 where no point
    const float32x4_t gi = vaddq_f32(vmulq_n_f32(vmulq_f32(qx, iz), in.fx), cx);
    const float32x4_t gj = vaddq_f32(vmulq_n_f32(vmulq_f32(qy, iz), in.fy), cy);
    valid = vandq_u32(valid, vandq_u32(vandq_u32(neon::greater_equal(gi, zero), neon::greater_equal(gj, zero)),
                                       vandq_u32(neon::less(gi, cols), neon::less(gj, rows))));
    if (!any(valid)) continue;
    // Truncation, as the reference's cast (both are >= 0 in a valid lane); sample 0 elsewhere,
    // read and never used.
    const int32x4_t k =
        vandq_s32(vmlaq_n_s32(vcvtq_s32_f32(gi), vcvtq_s32_f32(gj), in.cols), vreinterpretq_s32_u32(valid));
    float32x4x3_t n{}, target{};
    gather<0>(in, k, n, target);
    gather<1>(in, k, n, target);
    gather<2>(in, k, n, target);
    gather<3>(in, k, n, target);
    const float32x4_t dx = vsubq_f32(qx, target.val[0]), dy = vsubq_f32(qy, target.val[1]);
    const float32x4_t dz = vsubq_f32(qz, target.val[2]);
    const uint32x4_t no_normal =
        vandq_u32(vandq_u32(vceqq_f32(n.val[0], zero), vceqq_f32(n.val[1], zero)), vceqq_f32(n.val[2], zero));
    const float32x4_t d2 = vmlaq_f32(vmlaq_f32(vmulq_f32(dx, dx), dy, dy), dz, dz);
    valid = vbicq_u32(vbicq_u32(valid, no_normal), neon::greater(d2, max_d2));
    if (!any(valid)) continue;
    const float32x4_t sz_c = vmulq_f32(vmulq_n_f32(pz, in.coeff), pz);
    const float32x4_t sz_p = vmulq_f32(vmulq_n_f32(target.val[2], in.coeff), target.val[2]);
    const float32x4_t mx = dot3(R[0], n.val[0], R[3], n.val[1], R[6], n.val[2]);
    const float32x4_t my = dot3(R[1], n.val[0], R[4], n.val[1], R[7], n.val[2]);
    const float32x4_t mz = dot3(R[2], n.val[0], R[5], n.val[1], R[8], n.val[2]);
    const float32x4_t ax = vmlsq_n_f32(px, dot3(R[0], dx, R[3], dy, R[6], dz), 0.5f);
    const float32x4_t ay = vmlsq_n_f32(py, dot3(R[1], dx, R[4], dy, R[7], dz), 0.5f);
    const float32x4_t az = vmlsq_n_f32(pz, dot3(R[2], dx, R[5], dy, R[8], dz), 0.5f);
    float32x4x4_t head, tail;
    head.val[0] = vmlaq_f32(vmlaq_f32(vmulq_f32(n.val[0], dx), n.val[1], dy), n.val[2], dz);
    head.val[1] = reciprocal(vbslq_f32(valid, vaddq_f32(vmlaq_f32(vmulq_f32(sz_c, sz_c), sz_p, sz_p), floor2), one));
    head.val[2] = mx;
    head.val[3] = my;
    tail.val[0] = mz;
    tail.val[1] = vmlsq_f32(vmulq_f32(ay, mz), az, my);
    tail.val[2] = vmlsq_f32(vmulq_f32(az, mx), ax, mz);
    tail.val[3] = vmlsq_f32(vmulq_f32(ax, my), ay, mx);
    const int first = in.first_index + in.step * i0;
    if (vgetq_lane_u32(valid, 0) != 0) write<0>(head, tail, k, first, out + count++);
    if (vgetq_lane_u32(valid, 1) != 0) write<1>(head, tail, k, first + in.step, out + count++);
    if (vgetq_lane_u32(valid, 2) != 0) write<2>(head, tail, k, first + 2 * in.step, out + count++);
    if (vgetq_lane_u32(valid, 3) != 0) write<3>(head, tail, k, first + 3 * in.step, out + count++);
  }
  return count;
}

}  // namespace rgbdo::simd
