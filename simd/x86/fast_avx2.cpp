// AVX2 twin of simd/scalar/fast_scalar.cpp: 32 pixels at a time. The 16 circle comparisons
// become 16 byte-mask planes; 9 contiguous ones are found by the reference's doubling
// (runs of 2, 4, 8, then 9) applied to planes instead of bits. A block whose compass points
// (circle 0, 4, 8, 12) show no two adjacent ones on either side holds no corner and is
// skipped: every arc of 9 covers two adjacent compass points.
#include <immintrin.h>

#include <initializer_list>

#include "rgbd_odometry/simd/fast.hpp"

namespace rgbdo::simd {
namespace {

// The byte mask of pixels that have an arc of 9 among the 16 planes.
__m256i arc_of_9(const __m256i p[16]) {
  __m256i r2[16], r4[16];
  for (int k = 0; k < 16; ++k) r2[k] = _mm256_and_si256(p[k], p[(k + 1) & 15]);
  for (int k = 0; k < 16; ++k) r4[k] = _mm256_and_si256(r2[k], r2[(k + 2) & 15]);
  __m256i any = _mm256_setzero_si256();
  for (int k = 0; k < 16; ++k)
    any = _mm256_or_si256(any, _mm256_and_si256(_mm256_and_si256(r4[k], r4[(k + 4) & 15]), p[(k + 8) & 15]));
  return any;
}

}  // namespace

void fast9_row_avx2(const std::uint8_t* row, std::ptrdiff_t stride, int n, int threshold, std::uint8_t* flags) {
  std::ptrdiff_t offset[16];
  for (int k = 0; k < 16; ++k) offset[k] = kFastCircle[k][1] * stride + kFastCircle[k][0];
  const __m256i t = _mm256_set1_epi8(static_cast<char>(threshold > 255 ? 255 : threshold));
  const __m256i zero = _mm256_setzero_si256();
  const __m256i one = _mm256_set1_epi8(1), two = _mm256_set1_epi8(2);
  int i = 0;
  for (; i + 32 <= n; i += 32) {
    const std::uint8_t* p = row + i;
    const __m256i c = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
    // Saturated: centre + t above 255 leaves nothing brighter, centre - t below 0 nothing darker.
    const __m256i hi = _mm256_adds_epu8(c, t), lo = _mm256_subs_epu8(c, t);
    // v > hi  <=>  v -sat hi != 0;  v < lo  <=>  lo -sat v != 0 (unsigned bytes).
    const auto brighter = [&](const __m256i v) { return _mm256_xor_si256(_mm256_cmpeq_epi8(_mm256_subs_epu8(v, hi), zero), _mm256_set1_epi8(-1)); };
    const auto darker = [&](const __m256i v) { return _mm256_xor_si256(_mm256_cmpeq_epi8(_mm256_subs_epu8(lo, v), zero), _mm256_set1_epi8(-1)); };
    __m256i v[16];
    for (const int k : {0, 4, 8, 12}) v[k] = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + offset[k]));
    const __m256i b0 = brighter(v[0]), b4 = brighter(v[4]), b8 = brighter(v[8]), b12 = brighter(v[12]);
    const __m256i d0 = darker(v[0]), d4 = darker(v[4]), d8 = darker(v[8]), d12 = darker(v[12]);
    const __m256i maybe = _mm256_or_si256(
        _mm256_or_si256(_mm256_or_si256(_mm256_and_si256(b0, b4), _mm256_and_si256(b4, b8)),
                        _mm256_or_si256(_mm256_and_si256(b8, b12), _mm256_and_si256(b12, b0))),
        _mm256_or_si256(_mm256_or_si256(_mm256_and_si256(d0, d4), _mm256_and_si256(d4, d8)),
                        _mm256_or_si256(_mm256_and_si256(d8, d12), _mm256_and_si256(d12, d0))));
    if (_mm256_testz_si256(maybe, maybe)) {
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(flags + i), zero);
      continue;
    }
    for (int k = 0; k < 16; ++k)
      if (k % 4 != 0) v[k] = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + offset[k]));
    __m256i planes[16];
    for (int k = 0; k < 16; ++k) planes[k] = brighter(v[k]);
    const __m256i bright = arc_of_9(planes);
    for (int k = 0; k < 16; ++k) planes[k] = darker(v[k]);
    const __m256i dark = arc_of_9(planes);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(flags + i),
                        _mm256_or_si256(_mm256_and_si256(bright, one), _mm256_and_si256(dark, two)));
  }
  if (i < n) fast9_row_scalar(row + i, stride, n - i, threshold, flags + i);
}

}  // namespace rgbdo::simd
