// AVX2 twin of simd/scalar/fast_scalar.cpp: 32 pixels at a time. A block whose compass points
// (circle 0, 4, 8, 12) show no two adjacent hits on either side holds no corner and is
// skipped (every arc of 9 covers two adjacent compass points); in the others each lane counts
// its longest run of brighter and of darker circle pixels, a corner being a run of 9 (the same
// booleans as the reference's bit test).
#include <immintrin.h>

#include "rgbd_odometry/simd/fast.hpp"

namespace rgbdo::simd {
namespace {

// The segment test's flags for the 32 pixels at p.
void flag_block(const std::uint8_t* p, const std::ptrdiff_t* offset, __m256i t, std::uint8_t* flags) {
  const __m256i zero = _mm256_setzero_si256();
  const __m256i one = _mm256_set1_epi8(1), two = _mm256_set1_epi8(2);
  const __m256i c = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
  // Saturated: centre + t above 255 leaves nothing brighter, centre - t below 0 nothing darker.
  const __m256i hi = _mm256_adds_epu8(c, t), lo = _mm256_subs_epu8(c, t);
  // v > hi  <=>  v -sat hi != 0;  v < lo  <=>  lo -sat v != 0 (unsigned bytes).
  const auto brighter = [&](const __m256i v) { return _mm256_xor_si256(_mm256_cmpeq_epi8(_mm256_subs_epu8(v, hi), zero), _mm256_set1_epi8(-1)); };
  const auto darker = [&](const __m256i v) { return _mm256_xor_si256(_mm256_cmpeq_epi8(_mm256_subs_epu8(lo, v), zero), _mm256_set1_epi8(-1)); };
  const auto load = [&](int k) { return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + offset[k])); };
  const __m256i n0 = load(0), n4 = load(4), n8 = load(8), n12 = load(12);  // the compass points
  const __m256i b0 = brighter(n0), b4 = brighter(n4), b8 = brighter(n8), b12 = brighter(n12);
  const __m256i d0 = darker(n0), d4 = darker(n4), d8 = darker(n8), d12 = darker(n12);
  const __m256i maybe = _mm256_or_si256(
      _mm256_or_si256(_mm256_or_si256(_mm256_and_si256(b0, b4), _mm256_and_si256(b4, b8)),
                      _mm256_or_si256(_mm256_and_si256(b8, b12), _mm256_and_si256(b12, b0))),
      _mm256_or_si256(_mm256_or_si256(_mm256_and_si256(d0, d4), _mm256_and_si256(d4, d8)),
                      _mm256_or_si256(_mm256_and_si256(d8, d12), _mm256_and_si256(d12, d0))));
  if (_mm256_testz_si256(maybe, maybe)) {
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(flags), zero);
    return;
  }
  // Longest run of brighter (darker) circle pixels over one and a half turns (runs across
  // the circle's start seen whole); a corner has a run of 9.
  __m256i run_b = zero, run_d = zero, max_b = zero, max_d = zero;
  for (int k = 0; k < 24; ++k) {
    const __m256i x = load(k & 15);
    run_b = _mm256_and_si256(_mm256_add_epi8(run_b, one), brighter(x));
    run_d = _mm256_and_si256(_mm256_add_epi8(run_d, one), darker(x));
    max_b = _mm256_max_epu8(max_b, run_b);
    max_d = _mm256_max_epu8(max_d, run_d);
  }
  const __m256i eight = _mm256_set1_epi8(8);
  // max >= 9  <=>  max -sat 8 != 0
  const __m256i bright = _mm256_xor_si256(_mm256_cmpeq_epi8(_mm256_subs_epu8(max_b, eight), zero), _mm256_set1_epi8(-1));
  const __m256i dark = _mm256_xor_si256(_mm256_cmpeq_epi8(_mm256_subs_epu8(max_d, eight), zero), _mm256_set1_epi8(-1));
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(flags),
                      _mm256_or_si256(_mm256_and_si256(bright, one), _mm256_and_si256(dark, two)));
}

}  // namespace

void fast9_row_avx2(const std::uint8_t* row, std::ptrdiff_t stride, int n, int threshold, std::uint8_t* flags) {
  std::ptrdiff_t offset[16];
  for (int k = 0; k < 16; ++k) offset[k] = kFastCircle[k][1] * stride + kFastCircle[k][0];
  const __m256i t = _mm256_set1_epi8(static_cast<char>(threshold > 255 ? 255 : threshold));
  int i = 0;
  for (; i + 32 <= n; i += 32) flag_block(row + i, offset, t, flags + i);
  // The rest as the row's last 32 pixels, some of them flagged again alike: the scalar
  // reference tests one pixel for what a block tests thirty-two.
  if (i < n) {
    if (n >= 32) flag_block(row + n - 32, offset, t, flags + n - 32);
    else fast9_row_scalar(row + i, stride, n - i, threshold, flags + i);
  }
}

}  // namespace rgbdo::simd
