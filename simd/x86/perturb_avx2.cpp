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

// The reference's lane operations on a ymm register (perturb_reference.hpp).
struct Avx2Ops {
  using F = __m256;
  using U = __m256i;
  using M = __m256;
  static F set(float v) { return _mm256_set1_ps(v); }
  static F add(F a, F b) { return _mm256_add_ps(a, b); }
  static F sub(F a, F b) { return _mm256_sub_ps(a, b); }
  static F mul(F a, F b) { return _mm256_mul_ps(a, b); }
  static F div(F a, F b) { return _mm256_div_ps(a, b); }
  static F sqrt(F x) { return _mm256_sqrt_ps(x); }
  static M greater(F a, F b) { return _mm256_cmp_ps(a, b, _CMP_GT_OQ); }
  static M less(F a, F b) { return _mm256_cmp_ps(a, b, _CMP_LT_OQ); }
  static M either(M a, M b) { return _mm256_or_ps(a, b); }
  static F select(M m, F where_true, F where_false) { return _mm256_blendv_ps(where_false, where_true, m); }
  static F unit(U x) {
    return _mm256_mul_ps(_mm256_add_ps(_mm256_cvtepi32_ps(_mm256_srli_epi32(x, 9)), _mm256_set1_ps(0.5f)),
                         _mm256_set1_ps(0x1.0p-23f));
  }
  static U add_u(U a, U b) { return _mm256_add_epi32(a, b); }
  static U xor_u(U a, U b) { return _mm256_xor_si256(a, b); }
  static U or_u(U a, U b) { return _mm256_or_si256(a, b); }
  template <int N>
  static U shift_left(U x) { return _mm256_slli_epi32(x, N); }
  template <int N>
  static U shift_right(U x) { return _mm256_srli_epi32(x, N); }
  static void split(F u, F& exponent, F& mantissa) {
    const __m256i bits = _mm256_castps_si256(u);
    exponent = _mm256_cvtepi32_ps(_mm256_sub_epi32(_mm256_srli_epi32(bits, 23), _mm256_set1_epi32(127)));
    mantissa = _mm256_castsi256_ps(
        _mm256_or_si256(_mm256_and_si256(bits, _mm256_set1_epi32(0x007FFFFF)), _mm256_set1_epi32(0x3F800000)));
  }
};

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
      const __m256 w = _mm256_mul_ps(
          _mm256_set1_ps(in.w[k]),
          _mm256_loadu_ps(in.cell_weight + static_cast<long>(in.cell[k]) * in.perturbations + b * L));
      reference::accumulate_point_of<Avx2Ops>(in, k, w, st.s, S, D, M);
    }
    for (int j = 0; j < 3; ++j) {
      _mm256_storeu_ps(out.s[j] + b * L, S[j]);
      _mm256_storeu_ps(out.d[j] + b * L, D[j]);
    }
    for (int e = 0; e < 9; ++e) _mm256_storeu_ps(out.m[e] + b * L, M[e]);
  }
}

}  // namespace rgbdo::simd
