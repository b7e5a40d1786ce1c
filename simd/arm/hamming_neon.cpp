// NEON twin of simd/scalar/hamming_scalar.cpp (bit-exact, ties included), for 32-byte
// descriptors (ORB); other sizes take the scalar reference.
//
// Two query descriptors are held in registers and share every train descriptor loaded
// (register blocking: each 32-byte train load serves two distance computations). Per pair:
// VEOR, VCNT (per-byte popcount) and byte adds; four pairs are then folded together by
// pairwise adds (VPADD, VPADDL) into four 32-bit distances, on which the best/second
// bookkeeping of the query (4 lanes, merged at the end of the row) and of the 4 train
// columns runs branch-free. Train descriptors past the last multiple of 4 use scalar updates.
#include <arm_neon.h>

#include <vector>

#include "nearest_two_reference.hpp"

namespace rgbdo::simd {
namespace {

struct Scratch {
  std::vector<std::uint32_t> col_best, col_second;
  std::vector<std::int32_t> col_index;
};
thread_local Scratch scratch;

inline uint8x8_t pair_counts(uint8x16_t q_lo, uint8x16_t q_hi, uint8x16_t t_lo, uint8x16_t t_hi) {
  const uint8x16_t c = vaddq_u8(vcntq_u8(veorq_u8(q_lo, t_lo)), vcntq_u8(veorq_u8(q_hi, t_hi)));  // <= 16
  return vadd_u8(vget_low_u8(c), vget_high_u8(c));                                               // <= 32
}

// Q query descriptors (1 or 2) against the whole train set.
template <int Q>
void match_queries(const std::uint8_t* const* q, const int* q_index, const std::uint8_t* train, int n_train,
                   std::size_t train_stride, NearestTwo* query_out, Scratch& s) {
  uint8x16_t q_lo[Q], q_hi[Q];
  uint32x4_t row_best[Q], row_second[Q];
  int32x4_t row_index[Q];
  for (int k = 0; k < Q; ++k) {
    q_lo[k] = vld1q_u8(q[k]);
    q_hi[k] = vld1q_u8(q[k] + 16);
    row_best[k] = row_second[k] = vdupq_n_u32(UINT32_MAX);
    row_index[k] = vdupq_n_s32(-1);
  }
  const int32x4_t lane_offsets = {0, 1, 2, 3};
  int j = 0;
  for (; j + 4 <= n_train; j += 4) {
    uint8x8_t counts[Q][4];
    for (int t = 0; t < 4; ++t) {
      const std::uint8_t* tp = train + static_cast<std::size_t>(j + t) * train_stride;
      const uint8x16_t t_lo = vld1q_u8(tp), t_hi = vld1q_u8(tp + 16);
      for (int k = 0; k < Q; ++k) counts[k][t] = pair_counts(q_lo[k], q_hi[k], t_lo, t_hi);
    }
    const int32x4_t train_index = vaddq_s32(vdupq_n_s32(j), lane_offsets);
    for (int k = 0; k < Q; ++k) {
      // [c0 c1 c2 c3] -> four distances: two VPADD levels (<= 128 per byte), then widen.
      const uint8x8_t folded =
          vpadd_u8(vpadd_u8(counts[k][0], counts[k][1]), vpadd_u8(counts[k][2], counts[k][3]));
      const uint32x4_t d = vmovl_u16(vpaddl_u8(folded));

      const uint32x4_t row_less = vcltq_u32(d, row_best[k]);
      row_second[k] = vminq_u32(row_second[k], vmaxq_u32(row_best[k], d));
      row_best[k] = vminq_u32(row_best[k], d);
      row_index[k] = vbslq_s32(row_less, train_index, row_index[k]);

      std::uint32_t* cb = s.col_best.data() + j;
      std::uint32_t* cs = s.col_second.data() + j;
      std::int32_t* ci = s.col_index.data() + j;
      const uint32x4_t col_best = vld1q_u32(cb);
      const uint32x4_t col_less = vcltq_u32(d, col_best);
      vst1q_u32(cs, vminq_u32(vld1q_u32(cs), vmaxq_u32(col_best, d)));
      vst1q_u32(cb, vminq_u32(col_best, d));
      vst1q_s32(ci, vbslq_s32(col_less, vdupq_n_s32(q_index[k]), vld1q_s32(ci)));
    }
  }
  for (int k = 0; k < Q; ++k) {
    std::uint32_t best[4], second[4];
    std::int32_t index[4];
    vst1q_u32(best, row_best[k]);
    vst1q_u32(second, row_second[k]);
    vst1q_s32(index, row_index[k]);
    query_out[k] = reference::merge_lanes(best, second, index, 4);
  }
  // The last n_train % 4 descriptors, in the scalar reference's order.
  for (int k = 0; k < Q; ++k)
    for (int jt = j; jt < n_train; ++jt) {
      const std::uint32_t d = reference::hamming(q[k], train + static_cast<std::size_t>(jt) * train_stride, 32);
      reference::update(query_out[k], d, jt);
      NearestTwo col{s.col_index[static_cast<std::size_t>(jt)], s.col_best[static_cast<std::size_t>(jt)],
                     s.col_second[static_cast<std::size_t>(jt)]};
      reference::update(col, d, q_index[k]);
      s.col_index[static_cast<std::size_t>(jt)] = col.best_index;
      s.col_best[static_cast<std::size_t>(jt)] = col.best;
      s.col_second[static_cast<std::size_t>(jt)] = col.second;
    }
}

}  // namespace

void nearest_two_hamming_neon(const std::uint8_t* query, int n_query, std::size_t query_stride,
                              const std::uint8_t* train, int n_train, std::size_t train_stride, int bytes,
                              NearestTwo* query_out, NearestTwo* train_out) {
  if (bytes != 32 || n_query == 0 || n_train == 0) {
    reference::nearest_two(query, n_query, query_stride, train, n_train, train_stride, bytes, query_out, train_out);
    return;
  }
  auto& s = scratch;
  const auto n = static_cast<std::size_t>(n_train);
  s.col_best.assign(n, UINT32_MAX);
  s.col_second.assign(n, UINT32_MAX);
  s.col_index.assign(n, -1);
  int i = 0;
  for (; i + 2 <= n_query; i += 2) {
    const std::uint8_t* q[2] = {query + static_cast<std::size_t>(i) * query_stride,
                                query + static_cast<std::size_t>(i + 1) * query_stride};
    const int idx[2] = {i, i + 1};
    match_queries<2>(q, idx, train, n_train, train_stride, query_out + i, s);
  }
  if (i < n_query) {
    const std::uint8_t* q[1] = {query + static_cast<std::size_t>(i) * query_stride};
    const int idx[1] = {i};
    match_queries<1>(q, idx, train, n_train, train_stride, query_out + i, s);
  }
  for (std::size_t j = 0; j < n; ++j) train_out[j] = NearestTwo{s.col_index[j], s.col_best[j], s.col_second[j]};
}


// Two rows at a time: VEOR, VCNT and byte adds per row, then one pairwise fold of both.
RGBDO_HAMMING_ROWS(hamming_rows_neon) {
  if (bytes != 32) {
    reference::hamming_rows(query, train, train_stride, rows, n_rows, bytes, distances);
    return;
  }
  const uint8x16_t q_lo = vld1q_u8(query), q_hi = vld1q_u8(query + 16);
  int k = 0;
  for (; k + 2 <= n_rows; k += 2) {
    const std::uint8_t* a = train + static_cast<std::size_t>(rows[k]) * train_stride;
    const std::uint8_t* b = train + static_cast<std::size_t>(rows[k + 1]) * train_stride;
    const uint8x8_t ca = pair_counts(q_lo, q_hi, vld1q_u8(a), vld1q_u8(a + 16));
    const uint8x8_t cb = pair_counts(q_lo, q_hi, vld1q_u8(b), vld1q_u8(b + 16));
    // [ca cb] -> per row: 8 bytes of <= 32 -> two 32-bit sums
    const uint32x2_t d = vpadd_u32(vpaddl_u16(vpaddl_u8(ca)), vpaddl_u16(vpaddl_u8(cb)));
    vst1_u32(distances + k, d);
  }
  if (k < n_rows) distances[k] = reference::hamming(query, train + static_cast<std::size_t>(rows[k]) * train_stride, 32);
}

}  // namespace rgbdo::simd
