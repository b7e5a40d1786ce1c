// SSE4.1 twins of the image kernels (simd/scalar/image_scalar.cpp), bit-exact; the sse42 and
// avx2 sets use them (the rows are short: 16 bytes at a time is enough). The blends compute
// a * 256 - a * w + b * w in 16-bit lanes (exact: below 2^16); the horizontal pass gathers
// its 16 source bytes per group of eight outputs with PSHUFB. The depth test compares
// floats as the reference does (x86 keeps denormals unless told otherwise).
#include <smmintrin.h>

#include <cstring>

#include "disc_masks.hpp"
#include "rgbd_odometry/simd/image.hpp"

namespace rgbdo::simd {
namespace {

// Eight 16-bit lanes: (a * 256 - a * w + b * w + 128) >> 8.
inline __m128i blend8(__m128i a16, __m128i b16, __m128i w16) {
  const __m128i acc = _mm_add_epi16(_mm_sub_epi16(_mm_slli_epi16(a16, 8), _mm_mullo_epi16(a16, w16)), _mm_mullo_epi16(b16, w16));
  return _mm_srli_epi16(_mm_add_epi16(acc, _mm_set1_epi16(128)), 8);
}

inline std::int32_t sum_epi32(__m128i v) {
  v = _mm_add_epi32(v, _mm_shuffle_epi32(v, _MM_SHUFFLE(1, 0, 3, 2)));
  v = _mm_add_epi32(v, _mm_shuffle_epi32(v, _MM_SHUFFLE(2, 3, 0, 1)));
  return _mm_cvtsi128_si32(v);
}

}  // namespace

RGBDO_BLEND_ROWS(blend_rows_sse41) {
  const __m128i w16 = _mm_set1_epi16(static_cast<short>(w));
  int i = 0;
  for (; i + 16 <= n; i += 16) {
    const __m128i a = _mm_loadu_si128(reinterpret_cast<const __m128i*>(r0 + i));
    const __m128i b = _mm_loadu_si128(reinterpret_cast<const __m128i*>(r1 + i));
    const __m128i zero = _mm_setzero_si128();
    const __m128i lo = blend8(_mm_unpacklo_epi8(a, zero), _mm_unpacklo_epi8(b, zero), w16);
    const __m128i hi = blend8(_mm_unpackhi_epi8(a, zero), _mm_unpackhi_epi8(b, zero), w16);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + i), _mm_packus_epi16(lo, hi));
  }
  blend_rows_scalar(r0 + i, r1 + i, n - i, w, out + i);
}

RGBDO_RESAMPLE_ROW(resample_row_sse41) {
  const __m128i one = _mm_set1_epi8(1);
  int g = 0;
  for (; (g + 1) * 8 <= n; ++g) {
    const ResampleGroup& group = groups[g];
    const __m128i s = _mm_loadu_si128(reinterpret_cast<const __m128i*>(src + group.base));
    const __m128i index = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(group.index));
    const __m128i a = _mm_cvtepu8_epi16(_mm_shuffle_epi8(s, index));
    const __m128i b = _mm_cvtepu8_epi16(_mm_shuffle_epi8(s, _mm_add_epi8(index, one)));
    const __m128i w = _mm_cvtepu8_epi16(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(group.weight)));
    _mm_storel_epi64(reinterpret_cast<__m128i*>(out + g * 8), _mm_packus_epi16(blend8(a, b, w), _mm_setzero_si128()));
  }
  resample_row_scalar(src, groups + g, n - g * 8, out + g * 8);
}

namespace {

// Eight box sums, columns i..i+7.
void box5_block8(const std::uint8_t* centre, std::ptrdiff_t stride, int i, std::uint16_t* out) {
  // Column sums of columns i-2..i+5 (left) and i+2..i+9 (right): 8-byte loads reach no
  // further than the 2 pixels the caller keeps.
  const std::uint8_t* p = centre + i - 2 - 2 * stride;
  __m128i left = _mm_setzero_si128(), right = _mm_setzero_si128();
  for (int dy = 0; dy < 5; ++dy) {
    left = _mm_add_epi16(left, _mm_cvtepu8_epi16(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p + dy * stride))));
    right = _mm_add_epi16(right, _mm_cvtepu8_epi16(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p + 4 + dy * stride))));
  }
  // right's columns i+6..i+9 (lanes 4..7) follow left's i-2..i+5.
  const __m128i next = _mm_srli_si128(right, 8);
  __m128i sum = left;
  sum = _mm_add_epi16(sum, _mm_alignr_epi8(next, left, 2));
  sum = _mm_add_epi16(sum, _mm_alignr_epi8(next, left, 4));
  sum = _mm_add_epi16(sum, _mm_alignr_epi8(next, left, 6));
  sum = _mm_add_epi16(sum, _mm_alignr_epi8(next, left, 8));
  _mm_storeu_si128(reinterpret_cast<__m128i*>(out + i), sum);
}

}  // namespace

RGBDO_BOX5_ROW(box5_row_sse41) {
  if (n < 8) {
    box5_row_scalar(centre, stride, n, out);
    return;
  }
  for (int i = 0; i + 8 <= n; i += 8) box5_block8(centre, stride, i, out);
  // The last columns as one more block ending at the row's end, overlapping the one before
  // (the same sums written again): the scalar loop cost 0.5 M ARM instructions a frame.
  if (n % 8 != 0) box5_block8(centre, stride, n - 8, out);
}

RGBDO_DEPTH_IN_RANGE_ROW(depth_in_range_row_sse41) {
  const __m128 lov = _mm_set1_ps(lo), hiv = _mm_set1_ps(hi);
  int i = 0;
  for (; i + 16 <= n; i += 16) {
    __m128i m[4];
    for (int k = 0; k < 4; ++k) {
      const __m128 d = _mm_loadu_ps(depth + i + 4 * k);
      m[k] = _mm_castps_si128(_mm_and_ps(_mm_cmpge_ps(d, lov), _mm_cmple_ps(d, hiv)));  // NaN: false
    }
    const __m128i words = _mm_packs_epi32(m[0], m[1]), words2 = _mm_packs_epi32(m[2], m[3]);  // -1 or 0
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + i), _mm_packs_epi16(words, words2));   // 0xFF or 0
  }
  depth_in_range_row_scalar(depth + i, n - i, lo, hi, out + i);
}

RGBDO_DISC_MOMENTS(disc_moments_sse41) {
  // Signed column weights dx for PMADDUBSW (pixel * dx, pairs summed: at most 2 * 255 * 15).
  const __m128i dx_left = _mm_setr_epi8(-16, -15, -14, -13, -12, -11, -10, -9, -8, -7, -6, -5, -4, -3, -2, -1);
  const __m128i dx_right = _mm_setr_epi8(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  const __m128i ones = _mm_set1_epi16(1), zero = _mm_setzero_si128();
  __m128i weighted = zero;
  std::int32_t sy = 0;
  for (int dy = -kDiscRadius; dy <= kDiscRadius; ++dy) {
    const std::uint8_t* p = centre + dy * stride - 16;
    const std::uint8_t* m = kDiscMasks.row[dy + kDiscRadius];
    const __m128i a = _mm_and_si128(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p)),
                                    _mm_loadu_si128(reinterpret_cast<const __m128i*>(m)));
    const __m128i b = _mm_and_si128(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p + 16)),
                                    _mm_loadu_si128(reinterpret_cast<const __m128i*>(m + 16)));
    const __m128i pairs = _mm_add_epi16(_mm_maddubs_epi16(a, dx_left), _mm_maddubs_epi16(b, dx_right));
    weighted = _mm_add_epi32(weighted, _mm_madd_epi16(pairs, ones));
    const __m128i sad = _mm_add_epi64(_mm_sad_epu8(a, zero), _mm_sad_epu8(b, zero));
    sy += dy * (_mm_cvtsi128_si32(sad) + _mm_extract_epi32(sad, 2));
  }
  *m10 = sum_epi32(weighted);
  *m01 = sy;
}

}  // namespace rgbdo::simd
