// AVX2 twin of simd/scalar/hamming_scalar.cpp (bit-exact, ties included).
//
// Layout: the train set is re-laid once per call as blocks of 8 descriptors in "word
// planes": for 64-bit word w of a block, one register holds that word of the block's even
// descriptors (0, 2, 4, 6) and one of its odd ones. A query word broadcast to all lanes is
// XORed with a plane; the nibble-table popcount gives per-byte counts, which are summed over
// all words first (a byte holds at most 8 per word, so up to 31 words fit) and then reduced
// by one VPSADBW per plane: four distances per register. Shifting the odd distances into the
// high halves yields eight 32-bit distances in train order, on which the best/second
// bookkeeping for the query (8 lanes, merged at the end of the row) and for the 8 train
// descriptors (loaded, updated, stored) runs branch-free.
#include <immintrin.h>

#include <cstring>
#include <vector>

#include "nearest_two_reference.hpp"

namespace rgbdo::simd {
namespace {

constexpr int kBlock = 8;

// Scratch reused across calls: no allocation once the largest frame has been seen.
struct alignas(32) Plane {
  std::uint64_t lanes[4];
};

struct Scratch {
  std::vector<Plane> planes;
  std::vector<std::uint32_t> col_best, col_second;
  std::vector<std::int32_t> col_index;
};
thread_local Scratch scratch;

inline __m256i less_u32(__m256i a, __m256i b) {  // a < b, unsigned
  const __m256i bias = _mm256_set1_epi32(static_cast<int>(0x80000000u));
  return _mm256_cmpgt_epi32(_mm256_xor_si256(b, bias), _mm256_xor_si256(a, bias));
}

inline __m256i popcount_bytes(__m256i x) {
  const __m256i table = _mm256_setr_epi8(0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4, 0, 1, 1, 2, 1, 2, 2, 3, 1, 2,
                                         2, 3, 2, 3, 3, 4);
  const __m256i low4 = _mm256_set1_epi8(0x0f);
  const __m256i lo = _mm256_shuffle_epi8(table, _mm256_and_si256(x, low4));
  const __m256i hi = _mm256_shuffle_epi8(table, _mm256_and_si256(_mm256_srli_epi16(x, 4), low4));
  return _mm256_add_epi8(lo, hi);
}

}  // namespace

void nearest_two_hamming_avx2(const std::uint8_t* query, int n_query, std::size_t query_stride,
                              const std::uint8_t* train, int n_train, std::size_t train_stride, int bytes,
                              NearestTwo* query_out, NearestTwo* train_out) {
  const int words = bytes / 8;
  if (bytes % 8 != 0 || words > 31 || n_query == 0 || n_train == 0) {
    nearest_two_hamming_scalar(query, n_query, query_stride, train, n_train, train_stride, bytes, query_out, train_out);
    return;
  }
  const int blocks = (n_train + kBlock - 1) / kBlock;
  const auto padded = static_cast<std::size_t>(blocks * kBlock);
  auto& s = scratch;
  s.planes.resize(static_cast<std::size_t>(blocks * words * 2));
  s.col_best.assign(padded, UINT32_MAX);
  s.col_second.assign(padded, UINT32_MAX);
  s.col_index.assign(padded, -1);

  for (int b = 0; b < blocks; ++b)
    for (int w = 0; w < words; ++w)
      for (int parity = 0; parity < 2; ++parity) {
        Plane& p = s.planes[static_cast<std::size_t>((b * words + w) * 2 + parity)];
        for (int l = 0; l < 4; ++l) {
          const int j = b * kBlock + 2 * l + parity;
          p.lanes[l] = 0;
          if (j < n_train) std::memcpy(&p.lanes[l], train + static_cast<std::size_t>(j) * train_stride + 8 * w, 8);
        }
      }
  // Padding descriptors of the last block read as infinitely far away.
  alignas(32) std::uint32_t pad[kBlock];
  for (int l = 0; l < kBlock; ++l) pad[l] = (blocks - 1) * kBlock + l < n_train ? 0u : UINT32_MAX;
  const __m256i last_block_pad = _mm256_load_si256(reinterpret_cast<const __m256i*>(pad));
  const __m256i lane_offsets = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m256i zero = _mm256_setzero_si256();

  __m256i q[31];
  for (int i = 0; i < n_query; ++i) {
    const std::uint8_t* qi = query + static_cast<std::size_t>(i) * query_stride;
    for (int w = 0; w < words; ++w) {
      std::int64_t word;
      std::memcpy(&word, qi + 8 * w, 8);
      q[w] = _mm256_set1_epi64x(word);
    }
    __m256i row_best = _mm256_set1_epi32(-1), row_second = row_best, row_index = row_best;
    const __m256i query_index = _mm256_set1_epi32(i);
    const auto* plane = reinterpret_cast<const __m256i*>(s.planes.data());
    for (int b = 0; b < blocks; ++b) {
      __m256i even = zero, odd = zero;
      for (int w = 0; w < words; ++w, plane += 2) {
        even = _mm256_add_epi8(even, popcount_bytes(_mm256_xor_si256(plane[0], q[w])));
        odd = _mm256_add_epi8(odd, popcount_bytes(_mm256_xor_si256(plane[1], q[w])));
      }
      __m256i d = _mm256_or_si256(_mm256_sad_epu8(even, zero), _mm256_slli_epi64(_mm256_sad_epu8(odd, zero), 32));
      if (b == blocks - 1) d = _mm256_or_si256(d, last_block_pad);

      // Query row: best = min, second = min(second, max(best, d)), index where d < best.
      const __m256i row_less = less_u32(d, row_best);
      row_second = _mm256_min_epu32(row_second, _mm256_max_epu32(row_best, d));
      row_best = _mm256_min_epu32(row_best, d);
      row_index = _mm256_blendv_epi8(row_index, _mm256_add_epi32(_mm256_set1_epi32(b * kBlock), lane_offsets), row_less);

      // The block's 8 train columns, same rule with this query's index.
      auto* cb = reinterpret_cast<__m256i*>(s.col_best.data() + b * kBlock);
      auto* cs = reinterpret_cast<__m256i*>(s.col_second.data() + b * kBlock);
      auto* ci = reinterpret_cast<__m256i*>(s.col_index.data() + b * kBlock);
      const __m256i col_best = _mm256_loadu_si256(cb);
      const __m256i col_less = less_u32(d, col_best);
      _mm256_storeu_si256(cs, _mm256_min_epu32(_mm256_loadu_si256(cs), _mm256_max_epu32(col_best, d)));
      _mm256_storeu_si256(cb, _mm256_min_epu32(col_best, d));
      _mm256_storeu_si256(ci, _mm256_blendv_epi8(_mm256_loadu_si256(ci), query_index, col_less));
    }
    alignas(32) std::uint32_t best[kBlock], second[kBlock];
    alignas(32) std::int32_t index[kBlock];
    _mm256_store_si256(reinterpret_cast<__m256i*>(best), row_best);
    _mm256_store_si256(reinterpret_cast<__m256i*>(second), row_second);
    _mm256_store_si256(reinterpret_cast<__m256i*>(index), row_index);
    query_out[i] = reference::merge_lanes(best, second, index, kBlock);
  }
  for (int j = 0; j < n_train; ++j)
    train_out[j] = NearestTwo{s.col_index[static_cast<std::size_t>(j)], s.col_best[static_cast<std::size_t>(j)],
                              s.col_second[static_cast<std::size_t>(j)]};
}

}  // namespace rgbdo::simd
