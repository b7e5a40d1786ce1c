// Reference Hamming nearest-two kernel: plain loops, 64-bit popcount. The SIMD twins
// (simd/arm, simd/x86) must reproduce its output bit for bit.
#include <bit>
#include <cstring>

#include "nearest_two.hpp"

namespace rgbdo::simd {
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

inline void update(NearestTwo& n, std::uint32_t d, int index) {
  if (d < n.best) {
    n.second = n.best;
    n.best = d;
    n.best_index = index;
  } else if (d < n.second) {
    n.second = d;
  }
}

}  // namespace

void nearest_two_hamming_scalar(const std::uint8_t* query, int n_query, std::size_t query_stride,
                                const std::uint8_t* train, int n_train, std::size_t train_stride,
                                int bytes, NearestTwo* query_out, NearestTwo* train_out) {
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

}  // namespace rgbdo::simd
