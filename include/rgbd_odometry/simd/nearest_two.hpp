#pragma once
// Kernel interface for the symmetric ratio test: one pass over the query x train distance
// matrix yields, for every row of each set, its best and second-best distance into the
// other set and the index of the best. Each instruction set implements the same signature;
// simd/scalar/hamming_scalar.cpp is the reference every other one is tested against.
#include <cstddef>
#include <cstdint>

namespace rgbdo::simd {

struct NearestTwo {
  int best_index = -1;  // -1: the other set is empty
  std::uint32_t best = UINT32_MAX;
  std::uint32_t second = UINT32_MAX;  // UINT32_MAX: fewer than two candidates
};

// The rule every kernel keeps a record by, and the L2 matcher too: strict '<' keeps the lowest
// index among equal distances; a distance equal to the best becomes the second. Internal
// linkage (an unnamed namespace): files compiled with different instruction-set flags each
// keep their own copy, never one weak copy picked by the linker.
namespace {
inline void keep_nearest_two(NearestTwo& n, std::uint32_t d, int index) {
  if (d < n.best) {
    n.second = n.best;
    n.best = d;
    n.best_index = index;
  } else if (d < n.second) {
    n.second = d;
  }
}
}  // namespace

// Binary descriptors of `bytes` bytes, rows `stride` bytes apart (no alignment needed).
// Ties keep the lowest index. All kernels share this signature and this exact output.
#define RGBDO_NEAREST_TWO_HAMMING(name)                                                                       \
  void name(const std::uint8_t* query, int n_query, std::size_t query_stride, const std::uint8_t* train,     \
            int n_train, std::size_t train_stride, int bytes, NearestTwo* query_out, NearestTwo* train_out)
RGBDO_NEAREST_TWO_HAMMING(nearest_two_hamming_scalar);  // simd/scalar/hamming_scalar.cpp, the reference
RGBDO_NEAREST_TWO_HAMMING(nearest_two_hamming_popcnt);  // simd/x86/hamming_popcnt.cpp (x86-64 builds)
RGBDO_NEAREST_TWO_HAMMING(nearest_two_hamming_avx2);    // simd/x86/hamming_avx2.cpp (x86-64 builds)
RGBDO_NEAREST_TWO_HAMMING(nearest_two_hamming_neon);    // simd/arm/hamming_neon.cpp (ARM builds)

// The distances from one query descriptor to the train rows listed in `rows` (indices, any
// order): distances[k] = Hamming(query, train + rows[k] * train_stride) over `bytes` bytes.
// The windowed matcher's kernel (pipeline/match.hpp): its candidates are a few rows scattered
// over the train set, not the whole set.
#define RGBDO_HAMMING_ROWS(name)                                                                    \
  void name(const std::uint8_t* query, const std::uint8_t* train, std::size_t train_stride, const int* rows, \
            int n_rows, int bytes, std::uint32_t* distances)
RGBDO_HAMMING_ROWS(hamming_rows_scalar);  // simd/scalar/hamming_scalar.cpp, the reference
RGBDO_HAMMING_ROWS(hamming_rows_popcnt);  // simd/x86/hamming_popcnt.cpp (x86-64 builds: sse42 and avx2 sets)
RGBDO_HAMMING_ROWS(hamming_rows_neon);    // simd/arm/hamming_neon.cpp (ARM builds)

}  // namespace rgbdo::simd
