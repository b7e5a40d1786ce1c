// AVX2 twin of simd/scalar/perturb_scalar.cpp: the 8 lanes of the reference are the 8 lanes
// of a ymm register, operation for operation (no FMA: compiled without -mfma and with
// -ffp-contract=off), so the sums are bit-identical to the reference's.
#include <immintrin.h>

#include "perturb_reference.hpp"

namespace rgbdo::simd {
namespace {

struct Lanes {
  __m256i s[4];
};

inline __m256i next(Lanes& st) {  // xoshiro128+ in 8 lanes
  const __m256i result = _mm256_add_epi32(st.s[0], st.s[3]);
  const __m256i t = _mm256_slli_epi32(st.s[1], 9);
  st.s[2] = _mm256_xor_si256(st.s[2], st.s[0]);
  st.s[3] = _mm256_xor_si256(st.s[3], st.s[1]);
  st.s[1] = _mm256_xor_si256(st.s[1], st.s[2]);
  st.s[0] = _mm256_xor_si256(st.s[0], st.s[3]);
  st.s[2] = _mm256_xor_si256(st.s[2], t);
  st.s[3] = _mm256_or_si256(_mm256_slli_epi32(st.s[3], 11), _mm256_srli_epi32(st.s[3], 21));
  return result;
}

inline __m256 to_unit(__m256i x) {
  return _mm256_mul_ps(_mm256_add_ps(_mm256_cvtepi32_ps(_mm256_srli_epi32(x, 9)), _mm256_set1_ps(0.5f)),
                       _mm256_set1_ps(0x1.0p-23f));
}

// One Horner step, c + x2 * acc, in the reference's operation order.
inline __m256 poly(__m256 x2, __m256 acc, float c) { return _mm256_add_ps(_mm256_set1_ps(c), _mm256_mul_ps(x2, acc)); }

inline __m256 log_unit(__m256 u) {
  const __m256i bits = _mm256_castps_si256(u);
  __m256 e = _mm256_cvtepi32_ps(_mm256_sub_epi32(_mm256_srli_epi32(bits, 23), _mm256_set1_epi32(127)));
  __m256 m = _mm256_castsi256_ps(_mm256_or_si256(_mm256_and_si256(bits, _mm256_set1_epi32(0x007FFFFF)),
                                                 _mm256_set1_epi32(0x3F800000)));
  const __m256 fold = _mm256_cmp_ps(m, _mm256_set1_ps(1.41421356f), _CMP_GT_OQ);
  m = _mm256_blendv_ps(m, _mm256_mul_ps(m, _mm256_set1_ps(0.5f)), fold);
  e = _mm256_blendv_ps(e, _mm256_add_ps(e, _mm256_set1_ps(1.0f)), fold);
  const __m256 one = _mm256_set1_ps(1.0f);
  const __m256 s = _mm256_div_ps(_mm256_sub_ps(m, one), _mm256_add_ps(m, one));
  const __m256 s2 = _mm256_mul_ps(s, s);
  __m256 series = _mm256_set1_ps(0.111111111f);
  series = poly(s2, series, 0.142857143f);
  series = poly(s2, series, 0.2f);
  series = poly(s2, series, 0.333333333f);
  series = poly(s2, series, 1.0f);
  return _mm256_add_ps(_mm256_mul_ps(e, _mm256_set1_ps(0.693147181f)),
                       _mm256_mul_ps(_mm256_mul_ps(_mm256_set1_ps(2.0f), s), series));
}

inline void sincos_turns(__m256 t, __m256& sin_out, __m256& cos_out) {
  const __m256 upper = _mm256_cmp_ps(t, _mm256_set1_ps(0.25f), _CMP_GT_OQ);
  const __m256 lower = _mm256_cmp_ps(t, _mm256_set1_ps(-0.25f), _CMP_LT_OQ);
  const __m256 sign = _mm256_blendv_ps(_mm256_set1_ps(1.0f), _mm256_set1_ps(-1.0f), _mm256_or_ps(upper, lower));
  t = _mm256_blendv_ps(t, _mm256_sub_ps(_mm256_set1_ps(0.5f), t), upper);
  t = _mm256_blendv_ps(t, _mm256_sub_ps(_mm256_set1_ps(-0.5f), t), lower);
  const __m256 x = _mm256_mul_ps(t, _mm256_set1_ps(6.28318531f));
  const __m256 x2 = _mm256_mul_ps(x, x);
  __m256 sp = _mm256_set1_ps(-2.50521084e-8f);
  sp = poly(x2, sp, 2.75573192e-6f);
  sp = poly(x2, sp, -1.98412698e-4f);
  sp = poly(x2, sp, 8.33333333e-3f);
  sp = poly(x2, sp, -1.66666667e-1f);
  sp = poly(x2, sp, 1.0f);
  sin_out = _mm256_mul_ps(x, sp);
  __m256 cp = _mm256_set1_ps(2.08767570e-9f);
  cp = poly(x2, cp, -2.75573192e-7f);
  cp = poly(x2, cp, 2.48015873e-5f);
  cp = poly(x2, cp, -1.38888889e-3f);
  cp = poly(x2, cp, 4.16666667e-2f);
  cp = poly(x2, cp, -0.5f);
  cp = poly(x2, cp, 1.0f);
  cos_out = _mm256_mul_ps(sign, cp);
}

inline void box_muller(__m256i a, __m256i b, __m256& z0, __m256& z1) {
  const __m256 r = _mm256_sqrt_ps(_mm256_mul_ps(_mm256_set1_ps(-2.0f), log_unit(to_unit(a))));
  __m256 s, c;
  sincos_turns(_mm256_sub_ps(to_unit(b), _mm256_set1_ps(0.5f)), s, c);
  z0 = _mm256_mul_ps(r, c);
  z1 = _mm256_mul_ps(r, s);
}

inline __m256 add_mul(float base, float sigma, __m256 n) {
  return _mm256_add_ps(_mm256_set1_ps(base), _mm256_mul_ps(_mm256_set1_ps(sigma), n));
}

inline __m256 add_mul(__m256 base, float sigma, __m256 n) {
  return _mm256_add_ps(base, _mm256_mul_ps(_mm256_set1_ps(sigma), n));
}

}  // namespace

void perturbation_sums_avx2(const PerturbationInput& in, const PerturbationSums& out) {
  constexpr int L = kPerturbationLanes;
  Lanes st;
  {
    alignas(32) std::uint32_t lanes[4][L];
    for (int l = 0; l < L; ++l) {
      std::uint32_t s[4];
      reference::seed_lane(in.seed, l, s);
      for (int i = 0; i < 4; ++i) lanes[i][l] = s[i];
    }
    for (int i = 0; i < 4; ++i) st.s[i] = _mm256_load_si256(reinterpret_cast<const __m256i*>(lanes[i]));
  }
  for (int b = 0; b < in.perturbations / L; ++b) {
    __m256 S[3], D[3], M[9];
    for (auto& v : S) v = _mm256_setzero_ps();
    for (auto& v : D) v = _mm256_setzero_ps();
    for (auto& v : M) v = _mm256_setzero_ps();
    for (int k = 0; k < in.points; ++k) {
      __m256 n[6];
      for (int pair = 0; pair < 3; ++pair) {
        const __m256i a = next(st);
        const __m256i c = next(st);
        box_muller(a, c, n[2 * pair], n[2 * pair + 1]);
      }
      const __m256 s[3] = {add_mul(add_mul(in.sx[k], in.sigma_sx[k], n[0]), in.ray_sx[k], n[2]),
                           add_mul(add_mul(in.sy[k], in.sigma_sy[k], n[1]), in.ray_sy[k], n[2]),
                           add_mul(in.sz[k], in.ray_sz[k], n[2])};
      const __m256 d[3] = {add_mul(add_mul(in.dx[k], in.sigma_dx[k], n[3]), in.ray_dx[k], n[5]),
                           add_mul(add_mul(in.dy[k], in.sigma_dy[k], n[4]), in.ray_dy[k], n[5]),
                           add_mul(in.dz[k], in.ray_dz[k], n[5])};
      const __m256 w = _mm256_mul_ps(
          _mm256_set1_ps(in.w[k]),
          _mm256_loadu_ps(in.cell_weight + static_cast<long>(in.cell[k]) * in.perturbations + b * L));
      __m256 ws[3];
      for (int j = 0; j < 3; ++j) {
        ws[j] = _mm256_mul_ps(w, s[j]);
        S[j] = _mm256_add_ps(S[j], ws[j]);
        D[j] = _mm256_add_ps(D[j], _mm256_mul_ps(w, d[j]));
      }
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) M[3 * i + j] = _mm256_add_ps(M[3 * i + j], _mm256_mul_ps(d[i], ws[j]));
    }
    for (int j = 0; j < 3; ++j) {
      _mm256_storeu_ps(out.s[j] + b * L, S[j]);
      _mm256_storeu_ps(out.d[j] + b * L, D[j]);
    }
    for (int e = 0; e < 9; ++e) _mm256_storeu_ps(out.m[e] + b * L, M[e]);
  }
}

}  // namespace rgbdo::simd
