// SSE4.2-era twin of simd/scalar/hamming_scalar.cpp: the same loop, compiled with -mpopcnt
// so that each 64-bit word costs one POPCNT instruction instead of a bit-twiddling sequence.
#include "nearest_two_reference.hpp"

namespace rgbdo::simd {

void nearest_two_hamming_popcnt(const std::uint8_t* query, int n_query, std::size_t query_stride,
                                const std::uint8_t* train, int n_train, std::size_t train_stride, int bytes,
                                NearestTwo* query_out, NearestTwo* train_out) {
  reference::nearest_two(query, n_query, query_stride, train, n_train, train_stride, bytes, query_out, train_out);
}


RGBDO_HAMMING_ROWS(hamming_rows_popcnt) {
  reference::hamming_rows(query, train, train_stride, rows, n_rows, bytes, distances);
}

}  // namespace rgbdo::simd
