// AVX2 twin of simd/scalar/score_scalar.cpp: its 8 lanes in one ymm register, the same
// operations in the same order (no FMA), the same reduction tree; the tail (n % 8) masked.
#include <immintrin.h>

#include "rgbd_odometry/simd/score.hpp"

namespace rgbdo::simd {

void score_rigid_avx2(const RigidScoreInput& in, int& count, float& cost) {
  const __m256 r0 = _mm256_set1_ps(in.r[0]), r1 = _mm256_set1_ps(in.r[1]), r2 = _mm256_set1_ps(in.r[2]);
  const __m256 r3 = _mm256_set1_ps(in.r[3]), r4 = _mm256_set1_ps(in.r[4]), r5 = _mm256_set1_ps(in.r[5]);
  const __m256 r6 = _mm256_set1_ps(in.r[6]), r7 = _mm256_set1_ps(in.r[7]), r8 = _mm256_set1_ps(in.r[8]);
  const __m256 t0 = _mm256_set1_ps(in.t[0]), t1 = _mm256_set1_ps(in.t[1]), t2 = _mm256_set1_ps(in.t[2]);
  const __m256 thr = _mm256_set1_ps(in.threshold_sq);
  __m256 lane_cost = _mm256_setzero_ps();
  __m256i lane_count = _mm256_setzero_si256();
  const auto step = [&](__m256 px, __m256 py, __m256 pz, __m256 cx, __m256 cy, __m256 cz, __m256 valid) {
    const __m256 mx = _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(r0, cx), _mm256_mul_ps(r1, cy)), _mm256_mul_ps(r2, cz)), t0);
    const __m256 my = _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(r3, cx), _mm256_mul_ps(r4, cy)), _mm256_mul_ps(r5, cz)), t1);
    const __m256 mz = _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(r6, cx), _mm256_mul_ps(r7, cy)), _mm256_mul_ps(r8, cz)), t2);
    const __m256 ex = _mm256_sub_ps(px, mx), ey = _mm256_sub_ps(py, my), ez = _mm256_sub_ps(pz, mz);
    const __m256 e = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(ex, ex), _mm256_mul_ps(ey, ey)), _mm256_mul_ps(ez, ez));
    const __m256 inside = _mm256_and_ps(_mm256_cmp_ps(e, thr, _CMP_LT_OQ), valid);
    // Lanes past the end add 0 (the reference has no such lanes: adding +0.0 keeps its bits).
    const __m256 term = _mm256_and_ps(_mm256_blendv_ps(thr, e, inside), valid);
    lane_cost = _mm256_add_ps(lane_cost, term);
    lane_count = _mm256_sub_epi32(lane_count, _mm256_castps_si256(inside));  // true lanes are -1
  };
  const __m256 all = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
  int k = 0;
  for (; k + 8 <= in.n; k += 8)
    step(_mm256_loadu_ps(in.px + k), _mm256_loadu_ps(in.py + k), _mm256_loadu_ps(in.pz + k), _mm256_loadu_ps(in.cx + k),
         _mm256_loadu_ps(in.cy + k), _mm256_loadu_ps(in.cz + k), all);
  if (k < in.n) {
    alignas(32) float buf[6][8] = {};
    alignas(32) std::int32_t mask[8] = {};
    for (int l = 0; k + l < in.n; ++l) {
      buf[0][l] = in.px[k + l], buf[1][l] = in.py[k + l], buf[2][l] = in.pz[k + l];
      buf[3][l] = in.cx[k + l], buf[4][l] = in.cy[k + l], buf[5][l] = in.cz[k + l];
      mask[l] = -1;
    }
    step(_mm256_load_ps(buf[0]), _mm256_load_ps(buf[1]), _mm256_load_ps(buf[2]), _mm256_load_ps(buf[3]),
         _mm256_load_ps(buf[4]), _mm256_load_ps(buf[5]), _mm256_castsi256_ps(_mm256_load_si256(reinterpret_cast<const __m256i*>(mask))));
  }
  alignas(32) float c[8];
  alignas(32) std::int32_t n[8];
  _mm256_store_ps(c, lane_cost);
  _mm256_store_si256(reinterpret_cast<__m256i*>(n), lane_count);
  for (int l = 0; l < 4; ++l) c[l] = c[l] + c[l + 4];
  for (int l = 0; l < 2; ++l) c[l] = c[l] + c[l + 2];
  cost = c[0] + c[1];
  count = 0;
  for (int x : n) count += x;
}

}  // namespace rgbdo::simd
