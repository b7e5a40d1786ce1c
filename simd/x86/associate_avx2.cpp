// AVX2 twin of simd/scalar/associate_scalar.cpp: eight points a step, the reference's
// operations in its order (built without -mfma: no fused multiply-add), IEEE division as the
// reference's, the points and the previous grid's normals and points read by gathers. The
// associations found are written lane by lane.
#include <immintrin.h>

#include "rgbd_odometry/simd/associate.hpp"

namespace rgbdo::simd {
namespace {

// (a x + b y) + c z, as the reference rounds it.
inline __m256 dot3(float a, __m256 x, float b, __m256 y, float c, __m256 z) {
  return _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(a), x), _mm256_mul_ps(_mm256_set1_ps(b), y)),
                       _mm256_mul_ps(_mm256_set1_ps(c), z));
}

}  // namespace

int associate_avx2(const AssociateInput& in, Association* out) {
  const float* R = in.r;
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
  const __m256 cols = _mm256_set1_ps(static_cast<float>(in.cols)), rows = _mm256_set1_ps(static_cast<float>(in.rows));
  const __m256i lane_index = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  // Float offsets of the eight points taken, from the group's first.
  const __m256i point_offset = _mm256_mullo_epi32(lane_index, _mm256_set1_epi32(3 * in.step));
  int count = 0;
  for (int i0 = 0; i0 < in.n; i0 += 8) {
    // Lanes past the row's end are neither read nor associated.
    const __m256i present = _mm256_cmpgt_epi32(_mm256_set1_epi32(in.n - i0), lane_index);
    const __m256 present_ps = _mm256_castsi256_ps(present);
    const float* base = in.curr + 3 * in.step * i0;
    const __m256 px = _mm256_mask_i32gather_ps(zero, base, point_offset, present_ps, 4);
    const __m256 py = _mm256_mask_i32gather_ps(zero, base + 1, point_offset, present_ps, 4);
    const __m256 pz = _mm256_mask_i32gather_ps(zero, base + 2, point_offset, present_ps, 4);
    __m256 valid = _mm256_and_ps(present_ps, _mm256_cmp_ps(pz, zero, _CMP_NEQ_UQ));
    const __m256 qx = _mm256_add_ps(dot3(R[0], px, R[1], py, R[2], pz), _mm256_set1_ps(in.t[0]));
    const __m256 qy = _mm256_add_ps(dot3(R[3], px, R[4], py, R[5], pz), _mm256_set1_ps(in.t[1]));
    const __m256 qz = _mm256_add_ps(dot3(R[6], px, R[7], py, R[8], pz), _mm256_set1_ps(in.t[2]));
    valid = _mm256_and_ps(valid, _mm256_cmp_ps(qz, zero, _CMP_GT_OQ));
    if (_mm256_movemask_ps(valid) == 0) continue;
    // Divided where valid only (elsewhere 1 / 1), as the reference divides no other.
    const __m256 iz = _mm256_div_ps(one, _mm256_blendv_ps(one, qz, valid));
    const __m256 gi = _mm256_add_ps(_mm256_mul_ps(_mm256_mul_ps(qx, iz), _mm256_set1_ps(in.fx)), _mm256_set1_ps(in.cx));
    const __m256 gj = _mm256_add_ps(_mm256_mul_ps(_mm256_mul_ps(qy, iz), _mm256_set1_ps(in.fy)), _mm256_set1_ps(in.cy));
    valid = _mm256_and_ps(valid, _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(gi, zero, _CMP_GE_OQ), _mm256_cmp_ps(gj, zero, _CMP_GE_OQ)),
                                               _mm256_and_ps(_mm256_cmp_ps(gi, cols, _CMP_LT_OQ), _mm256_cmp_ps(gj, rows, _CMP_LT_OQ))));
    if (_mm256_movemask_ps(valid) == 0) continue;
    // Truncation, as the reference's cast; lanes not valid read sample 0, never used.
    const __m256i k = _mm256_and_si256(
        _mm256_add_epi32(_mm256_mullo_epi32(_mm256_cvttps_epi32(gj), _mm256_set1_epi32(in.cols)), _mm256_cvttps_epi32(gi)),
        _mm256_castps_si256(valid));
    const __m256i k3 = _mm256_mullo_epi32(k, _mm256_set1_epi32(3));
    const __m256 nx = _mm256_mask_i32gather_ps(zero, in.prev_normal, k3, valid, 4);
    const __m256 ny = _mm256_mask_i32gather_ps(zero, in.prev_normal + 1, k3, valid, 4);
    const __m256 nz = _mm256_mask_i32gather_ps(zero, in.prev_normal + 2, k3, valid, 4);
    const __m256 dx = _mm256_sub_ps(qx, _mm256_mask_i32gather_ps(zero, in.prev_point, k3, valid, 4));
    const __m256 dy = _mm256_sub_ps(qy, _mm256_mask_i32gather_ps(zero, in.prev_point + 1, k3, valid, 4));
    const __m256 tz = _mm256_mask_i32gather_ps(zero, in.prev_point + 2, k3, valid, 4);
    const __m256 dz = _mm256_sub_ps(qz, tz);
    const __m256 no_normal = _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(nx, zero, _CMP_EQ_OQ), _mm256_cmp_ps(ny, zero, _CMP_EQ_OQ)),
                                           _mm256_cmp_ps(nz, zero, _CMP_EQ_OQ));
    const __m256 d2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
    valid = _mm256_andnot_ps(_mm256_cmp_ps(d2, _mm256_set1_ps(in.max_d2), _CMP_GT_OQ), _mm256_andnot_ps(no_normal, valid));
    const int mask = _mm256_movemask_ps(valid);
    if (mask == 0) continue;
    const __m256 coeff = _mm256_set1_ps(in.coeff);
    const __m256 sz_c = _mm256_mul_ps(_mm256_mul_ps(coeff, pz), pz), sz_p = _mm256_mul_ps(_mm256_mul_ps(coeff, tz), tz);
    const __m256 w = _mm256_div_ps(
        one, _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(sz_c, sz_c), _mm256_mul_ps(sz_p, sz_p)), _mm256_set1_ps(in.floor2)));
    const __m256 mx = dot3(R[0], nx, R[3], ny, R[6], nz);
    const __m256 my = dot3(R[1], nx, R[4], ny, R[7], nz);
    const __m256 mz = dot3(R[2], nx, R[5], ny, R[8], nz);
    const __m256 half = _mm256_set1_ps(0.5f);
    const __m256 ax = _mm256_sub_ps(px, _mm256_mul_ps(dot3(R[0], dx, R[3], dy, R[6], dz), half));
    const __m256 ay = _mm256_sub_ps(py, _mm256_mul_ps(dot3(R[1], dx, R[4], dy, R[7], dz), half));
    const __m256 az = _mm256_sub_ps(pz, _mm256_mul_ps(dot3(R[2], dx, R[5], dy, R[8], dz), half));
    alignas(32) float v[8][8];
    alignas(32) std::int32_t ks[8];
    _mm256_store_ps(v[0], _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(nx, dx), _mm256_mul_ps(ny, dy)), _mm256_mul_ps(nz, dz)));
    _mm256_store_ps(v[1], w);
    _mm256_store_ps(v[2], mx);
    _mm256_store_ps(v[3], my);
    _mm256_store_ps(v[4], mz);
    _mm256_store_ps(v[5], _mm256_sub_ps(_mm256_mul_ps(ay, mz), _mm256_mul_ps(az, my)));
    _mm256_store_ps(v[6], _mm256_sub_ps(_mm256_mul_ps(az, mx), _mm256_mul_ps(ax, mz)));
    _mm256_store_ps(v[7], _mm256_sub_ps(_mm256_mul_ps(ax, my), _mm256_mul_ps(ay, mx)));
    _mm256_store_si256(reinterpret_cast<__m256i*>(ks), k);
    for (int l = 0; l < 8; ++l)
      if ((mask >> l) & 1) {
        Association& a = out[count++];
        a.r = v[0][l];
        a.w = v[1][l];
        for (int e = 0; e < 6; ++e) a.j[e] = v[2 + e][l];
        a.curr_index = in.first_index + in.step * (i0 + l);
        a.prev_index = ks[l];
      }
  }
  return count;
}

}  // namespace rgbdo::simd
