// Reference Hamming nearest-two kernel: the plain loop of nearest_two_reference.hpp,
// compiled for the baseline instruction set. The SIMD twins (simd/arm, simd/x86) must
// reproduce its output bit for bit.
#include "nearest_two_reference.hpp"

namespace rgbdo::simd {

void nearest_two_hamming_scalar(const std::uint8_t* query, int n_query, std::size_t query_stride,
                                const std::uint8_t* train, int n_train, std::size_t train_stride, int bytes,
                                NearestTwo* query_out, NearestTwo* train_out) {
  reference::nearest_two(query, n_query, query_stride, train, n_train, train_stride, bytes, query_out, train_out);
}


RGBDO_HAMMING_ROWS(hamming_rows_scalar) {
  reference::hamming_rows(query, train, train_stride, rows, n_rows, bytes, distances);
}

}  // namespace rgbdo::simd
