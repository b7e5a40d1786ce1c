#pragma once
// Test frames for the link tests: each says which one it is (the sequence number in its first
// four bytes, then a pattern derived from it), so order and loss can be read off the far end.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace rgbdo::link_test {

using Bytes = std::vector<std::uint8_t>;

inline Bytes make_frame(std::uint32_t seq, std::size_t size) {
  Bytes f(size);
  for (std::size_t i = 0; i < size; ++i) f[i] = static_cast<std::uint8_t>(seq * 31 + i * 7);
  for (std::size_t i = 0; i < 4 && i < size; ++i) f[i] = static_cast<std::uint8_t>(seq >> (8 * i));
  return f;
}

inline std::uint32_t frame_seq(const std::uint8_t* f) {
  return static_cast<std::uint32_t>(f[0]) | static_cast<std::uint32_t>(f[1]) << 8 |
         static_cast<std::uint32_t>(f[2]) << 16 | static_cast<std::uint32_t>(f[3]) << 24;
}

}  // namespace rgbdo::link_test
