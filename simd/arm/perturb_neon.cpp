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

inline uint32x4_t next(Half& st) {
  const uint32x4_t result = vaddq_u32(st.s[0], st.s[3]);
  const uint32x4_t t = vshlq_n_u32(st.s[1], 9);
  st.s[2] = veorq_u32(st.s[2], st.s[0]);
  st.s[3] = veorq_u32(st.s[3], st.s[1]);
  st.s[1] = veorq_u32(st.s[1], st.s[2]);
  st.s[0] = veorq_u32(st.s[0], st.s[3]);
  st.s[2] = veorq_u32(st.s[2], t);
  st.s[3] = vorrq_u32(vshlq_n_u32(st.s[3], 11), vshrq_n_u32(st.s[3], 21));
  return result;
}

inline float32x4_t divide(float32x4_t a, float32x4_t b) {
  float32x4_t r = vrecpeq_f32(b);
  r = vmulq_f32(r, vrecpsq_f32(b, r));
  r = vmulq_f32(r, vrecpsq_f32(b, r));
  return vmulq_f32(a, r);
}

// x >= 0; x = 0 would give 0 * inf = NaN through the estimate, so it is selected out.
inline float32x4_t sqrt_non_negative(float32x4_t x) {
  float32x4_t r = vrsqrteq_f32(x);
  r = vmulq_f32(r, vrsqrtsq_f32(vmulq_f32(x, r), r));
  r = vmulq_f32(r, vrsqrtsq_f32(vmulq_f32(x, r), r));
  return vbslq_f32(neon::greater(x, vdupq_n_f32(0.0f)), vmulq_f32(x, r), vdupq_n_f32(0.0f));
}

inline float32x4_t to_unit(uint32x4_t x) {
  return vmulq_f32(vaddq_f32(vcvtq_f32_u32(vshrq_n_u32(x, 9)), vdupq_n_f32(0.5f)), vdupq_n_f32(0x1.0p-23f));
}

// One Horner step, c + x2 * acc, in the reference's operation order.
inline float32x4_t poly(float32x4_t x2, float32x4_t acc, float c) { return vaddq_f32(vdupq_n_f32(c), vmulq_f32(x2, acc)); }

inline float32x4_t log_unit(float32x4_t u) {
  const uint32x4_t bits = vreinterpretq_u32_f32(u);
  float32x4_t e = vcvtq_f32_s32(vsubq_s32(vreinterpretq_s32_u32(vshrq_n_u32(bits, 23)), vdupq_n_s32(127)));
  float32x4_t m = vreinterpretq_f32_u32(vorrq_u32(vandq_u32(bits, vdupq_n_u32(0x007FFFFF)), vdupq_n_u32(0x3F800000)));
  const uint32x4_t fold = neon::greater(m, vdupq_n_f32(1.41421356f));
  m = vbslq_f32(fold, vmulq_f32(m, vdupq_n_f32(0.5f)), m);
  e = vbslq_f32(fold, vaddq_f32(e, vdupq_n_f32(1.0f)), e);
  const float32x4_t one = vdupq_n_f32(1.0f);
  const float32x4_t s = divide(vsubq_f32(m, one), vaddq_f32(m, one));
  const float32x4_t s2 = vmulq_f32(s, s);
  float32x4_t series = vdupq_n_f32(0.111111111f);
  series = poly(s2, series, 0.142857143f);
  series = poly(s2, series, 0.2f);
  series = poly(s2, series, 0.333333333f);
  series = poly(s2, series, 1.0f);
  return vaddq_f32(vmulq_f32(e, vdupq_n_f32(0.693147181f)), vmulq_f32(vmulq_f32(vdupq_n_f32(2.0f), s), series));
}

inline void sincos_turns(float32x4_t t, float32x4_t& sin_out, float32x4_t& cos_out) {
  const uint32x4_t upper = neon::greater(t, vdupq_n_f32(0.25f));
  const uint32x4_t lower = neon::less(t, vdupq_n_f32(-0.25f));
  const float32x4_t sign = vbslq_f32(vorrq_u32(upper, lower), vdupq_n_f32(-1.0f), vdupq_n_f32(1.0f));
  t = vbslq_f32(upper, vsubq_f32(vdupq_n_f32(0.5f), t), t);
  t = vbslq_f32(lower, vsubq_f32(vdupq_n_f32(-0.5f), t), t);
  const float32x4_t x = vmulq_f32(t, vdupq_n_f32(6.28318531f));
  const float32x4_t x2 = vmulq_f32(x, x);
  float32x4_t sp = vdupq_n_f32(-2.50521084e-8f);
  sp = poly(x2, sp, 2.75573192e-6f);
  sp = poly(x2, sp, -1.98412698e-4f);
  sp = poly(x2, sp, 8.33333333e-3f);
  sp = poly(x2, sp, -1.66666667e-1f);
  sp = poly(x2, sp, 1.0f);
  sin_out = vmulq_f32(x, sp);
  float32x4_t cp = vdupq_n_f32(2.08767570e-9f);
  cp = poly(x2, cp, -2.75573192e-7f);
  cp = poly(x2, cp, 2.48015873e-5f);
  cp = poly(x2, cp, -1.38888889e-3f);
  cp = poly(x2, cp, 4.16666667e-2f);
  cp = poly(x2, cp, -0.5f);
  cp = poly(x2, cp, 1.0f);
  cos_out = vmulq_f32(sign, cp);
}

inline void box_muller(uint32x4_t a, uint32x4_t b, float32x4_t& z0, float32x4_t& z1) {
  const float32x4_t r = sqrt_non_negative(vmulq_f32(vdupq_n_f32(-2.0f), log_unit(to_unit(a))));
  float32x4_t s, c;
  sincos_turns(vsubq_f32(to_unit(b), vdupq_n_f32(0.5f)), s, c);
  z0 = vmulq_f32(r, c);
  z1 = vmulq_f32(r, s);
}

inline float32x4_t add_mul(float base, float sigma, float32x4_t n) {
  return vaddq_f32(vdupq_n_f32(base), vmulq_f32(vdupq_n_f32(sigma), n));
}

inline float32x4_t add_mul(float32x4_t base, float sigma, float32x4_t n) {
  return vaddq_f32(base, vmulq_f32(vdupq_n_f32(sigma), n));
}

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
        float32x4_t n[6];
        for (int pair = 0; pair < 3; ++pair) {
          const uint32x4_t a = next(st[h]);
          const uint32x4_t c = next(st[h]);
          box_muller(a, c, n[2 * pair], n[2 * pair + 1]);
        }
        const float32x4_t s[3] = {add_mul(add_mul(in.sx[k], in.sigma_sx[k], n[0]), in.ray_sx[k], n[2]),
                                  add_mul(add_mul(in.sy[k], in.sigma_sy[k], n[1]), in.ray_sy[k], n[2]),
                                  add_mul(in.sz[k], in.ray_sz[k], n[2])};
        const float32x4_t d[3] = {add_mul(add_mul(in.dx[k], in.sigma_dx[k], n[3]), in.ray_dx[k], n[5]),
                                  add_mul(add_mul(in.dy[k], in.sigma_dy[k], n[4]), in.ray_dy[k], n[5]),
                                  add_mul(in.dz[k], in.ray_dz[k], n[5])};
        float32x4_t ws[3];
        for (int j = 0; j < 3; ++j) {
          ws[j] = vmulq_f32(w, s[j]);
          S[h][j] = vaddq_f32(S[h][j], ws[j]);
          D[h][j] = vaddq_f32(D[h][j], vmulq_f32(w, d[j]));
        }
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) M[h][3 * i + j] = vaddq_f32(M[h][3 * i + j], vmulq_f32(d[i], ws[j]));
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
