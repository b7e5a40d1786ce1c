#pragma once
// The reference nearest-two algorithm, so that the scalar set and the x86 popcnt set compile
// the very same loop (the latter with the POPCNT instruction). Every SIMD kernel must
// reproduce its output bit for bit, ties included.
//
// Translation units with different instruction-set flags include this file, so its functions
// have internal linkage (an unnamed namespace): with plain `inline` the linker would keep one
// weak copy for all of them, and an unoptimised build could run the POPCNT copy inside the
// scalar kernel, on a CPU without the instruction.
#include <bit>
#include <cstring>

#include "rgbd_odometry/simd/nearest_two.hpp"

namespace rgbdo::simd::reference {
namespace {

inline std::uint32_t hamming(const std::uint8_t* a, const std::uint8_t* b, int bytes) {
  std::uint32_t d = 0;
  int i = 0;
  for (; i + 8 <= bytes; i += 8) {
    std::uint64_t x, y;
    std::memcpy(&x, a + i, 8);  // memcpy: descriptor rows need not be 8-byte aligned
    std::memcpy(&y, b + i, 8);
    d += static_cast<std::uint32_t>(std::popcount(x ^ y));
  }
  for (; i < bytes; ++i) d += static_cast<std::uint32_t>(std::popcount(static_cast<unsigned>(a[i] ^ b[i])));
  return d;
}

// The record-keeping rule of nearest_two.hpp.
inline void update(NearestTwo& n, std::uint32_t d, int index) { keep_nearest_two(n, d, index); }

inline void nearest_two(const std::uint8_t* query, int n_query, std::size_t query_stride, const std::uint8_t* train,
                        int n_train, std::size_t train_stride, int bytes, NearestTwo* query_out,
                        NearestTwo* train_out) {
  for (int i = 0; i < n_query; ++i) query_out[i] = NearestTwo{};
  for (int j = 0; j < n_train; ++j) train_out[j] = NearestTwo{};
  for (int i = 0; i < n_query; ++i) {
    const std::uint8_t* q = query + static_cast<std::size_t>(i) * query_stride;
    for (int j = 0; j < n_train; ++j) {
      const std::uint32_t d = hamming(q, train + static_cast<std::size_t>(j) * train_stride, bytes);
      update(query_out[i], d, j);
      update(train_out[j], d, i);
    }
  }
}

inline void hamming_rows(const std::uint8_t* query, const std::uint8_t* train, std::size_t train_stride, const int* rows,
                         int n_rows, int bytes, std::uint32_t* distances) {
  for (int k = 0; k < n_rows; ++k)
    distances[k] = hamming(query, train + static_cast<std::size_t>(rows[k]) * train_stride, bytes);
}

// Merges per-lane row records of a vector kernel (lane l saw descriptors l, l + L, ...): the
// lowest index among the smallest bests wins; the second is the smallest of the winner's
// second and every other lane's best. Equals the record one scalar pass would have built.
inline NearestTwo merge_lanes(const std::uint32_t* best, const std::uint32_t* second, const std::int32_t* index,
                              int lanes) {
  int winner = 0;
  for (int l = 1; l < lanes; ++l)
    if (best[l] < best[winner] ||
        (best[l] == best[winner] && static_cast<std::uint32_t>(index[l]) < static_cast<std::uint32_t>(index[winner])))
      winner = l;
  NearestTwo out;
  out.best = best[winner];
  out.best_index = best[winner] == UINT32_MAX ? -1 : index[winner];
  out.second = second[winner];
  for (int l = 0; l < lanes; ++l)
    if (l != winner && best[l] < out.second) out.second = best[l];
  return out;
}

}  // namespace
}  // namespace rgbdo::simd::reference

// A kernel set's two Hamming kernels as the reference loops above, compiled with the including
// file's instruction-set flags (hamming_scalar.cpp: the baseline; hamming_popcnt.cpp: POPCNT).
#define RGBDO_HAMMING_KERNELS_FROM_REFERENCE(suffix)                                                               \
  void nearest_two_hamming_##suffix(const std::uint8_t* query, int n_query, std::size_t query_stride,              \
                                    const std::uint8_t* train, int n_train, std::size_t train_stride, int bytes,    \
                                    NearestTwo* query_out, NearestTwo* train_out) {                                 \
    reference::nearest_two(query, n_query, query_stride, train, n_train, train_stride, bytes, query_out, train_out); \
  }                                                                                                                  \
  RGBDO_HAMMING_ROWS(hamming_rows_##suffix) {                                                                        \
    reference::hamming_rows(query, train, train_stride, rows, n_rows, bytes, distances);                             \
  }
