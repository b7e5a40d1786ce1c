// NEON twin of simd/scalar/perturb_scalar.cpp: the reference's 8 lanes as two q registers
// of 4, operation for operation, except that ARMv7 NEON has no vector divide or square
// root: those use the reciprocal (square-root) estimate and two Newton-Raphson steps, which
// agree with IEEE division and sqrt to a few ulp (tested against the reference at 2e-6).
#include <arm_neon.h>

#include "neon_compare.hpp"
#include "perturb_reference.hpp"

namespace rgbdo::simd {
namespace {

struct Half {  // xoshiro128+ state of 4 lanes
  uint32x4_t s[4];
};

// The reference's lane operations on a q register (perturb_reference.hpp). ARMv7 NEON has no
// vector divide or square root: the reciprocal (square-root) estimate and two Newton-Raphson steps.
struct NeonOps {
  using F = float32x4_t;
  using U = uint32x4_t;
  using M = uint32x4_t;
  static F set(float v) { return vdupq_n_f32(v); }
  static F add(F a, F b) { return vaddq_f32(a, b); }
  static F sub(F a, F b) { return vsubq_f32(a, b); }
  static F mul(F a, F b) { return vmulq_f32(a, b); }
  static F div(F a, F b) {
    float32x4_t r = vrecpeq_f32(b);
    r = vmulq_f32(r, vrecpsq_f32(b, r));
    r = vmulq_f32(r, vrecpsq_f32(b, r));
    return vmulq_f32(a, r);
  }
  // x >= 0; x = 0 would give 0 * inf = NaN through the estimate, so it is selected out.
  static F sqrt(F x) {
    float32x4_t r = vrsqrteq_f32(x);
    r = vmulq_f32(r, vrsqrtsq_f32(vmulq_f32(x, r), r));
    r = vmulq_f32(r, vrsqrtsq_f32(vmulq_f32(x, r), r));
    return vbslq_f32(neon::greater(x, vdupq_n_f32(0.0f)), vmulq_f32(x, r), vdupq_n_f32(0.0f));
  }
  static M greater(F a, F b) { return neon::greater(a, b); }
  static M less(F a, F b) { return neon::less(a, b); }
  static M either(M a, M b) { return vorrq_u32(a, b); }
  static F select(M m, F where_true, F where_false) { return vbslq_f32(m, where_true, where_false); }
  static F unit(U x) {
    return vmulq_f32(vaddq_f32(vcvtq_f32_u32(vshrq_n_u32(x, 9)), vdupq_n_f32(0.5f)), vdupq_n_f32(0x1.0p-23f));
  }
  static U add_u(U a, U b) { return vaddq_u32(a, b); }
  static U xor_u(U a, U b) { return veorq_u32(a, b); }
  static U or_u(U a, U b) { return vorrq_u32(a, b); }
  template <int N>
  static U shift_left(U x) { return vshlq_n_u32(x, N); }
  template <int N>
  static U shift_right(U x) { return vshrq_n_u32(x, N); }
  static void split(F u, F& exponent, F& mantissa) {
    const uint32x4_t bits = vreinterpretq_u32_f32(u);
    exponent = vcvtq_f32_s32(vsubq_s32(vreinterpretq_s32_u32(vshrq_n_u32(bits, 23)), vdupq_n_s32(127)));
    mantissa = vreinterpretq_f32_u32(vorrq_u32(vandq_u32(bits, vdupq_n_u32(0x007FFFFF)), vdupq_n_u32(0x3F800000)));
  }
};

}  // namespace

void perturbation_sums_neon(const PerturbationInput& in, const PerturbationSums& out) {
  constexpr int L = kPerturbationLanes;
  Half st[2];
  for (int h = 0; h < 2; ++h) {
    std::uint32_t lanes[4][4];
    for (int l = 0; l < 4; ++l) {
      std::uint32_t s[4];
      reference::seed_lane(in.seed, 4 * h + l, s);
      for (int i = 0; i < 4; ++i) lanes[i][l] = s[i];
    }
    for (int i = 0; i < 4; ++i) st[h].s[i] = vld1q_u32(lanes[i]);
  }
  for (int b = 0; b < in.perturbations / L; ++b) {
    float32x4_t S[2][3], D[2][3], M[2][9];
    for (int h = 0; h < 2; ++h) {
      for (auto& v : S[h]) v = vdupq_n_f32(0);
      for (auto& v : D[h]) v = vdupq_n_f32(0);
      for (auto& v : M[h]) v = vdupq_n_f32(0);
    }
    for (int k = 0; k < in.points; ++k) {
      const float* g = in.cell_weight + static_cast<long>(in.cell[k]) * in.perturbations + b * L;
      for (int h = 0; h < 2; ++h) {
        const float32x4_t w = vmulq_f32(vdupq_n_f32(in.w[k]), vld1q_f32(g + 4 * h));
        reference::accumulate_point_of<NeonOps>(in, k, w, st[h].s, S[h], D[h], M[h]);
      }
    }
    for (int h = 0; h < 2; ++h) {
      for (int j = 0; j < 3; ++j) {
        vst1q_f32(out.s[j] + b * L + 4 * h, S[h][j]);
        vst1q_f32(out.d[j] + b * L + 4 * h, D[h][j]);
      }
      for (int e = 0; e < 9; ++e) vst1q_f32(out.m[e] + b * L + 4 * h, M[h][e]);
    }
  }
}

}  // namespace rgbdo::simd
