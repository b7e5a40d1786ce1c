#pragma once
// The orientation disc (rgbd_odometry/simd/image.hpp, kDiscHalfWidth15) as byte masks over
// the 32 columns -16..15 of its centre, one row per dy: the vector moments kernels AND a
// row's pixels with it. Internal linkage: each instruction-set file keeps its own copy.
#include <cstdint>

#include "rgbd_odometry/simd/image.hpp"

namespace rgbdo::simd {
namespace {

struct DiscMasks {
  std::uint8_t row[2 * kDiscRadius + 1][32];
  DiscMasks() : row{} {
    for (int dy = -kDiscRadius; dy <= kDiscRadius; ++dy) {
      const int hw = kDiscHalfWidth15[dy < 0 ? -dy : dy];
      for (int dx = -hw; dx <= hw; ++dx) row[dy + kDiscRadius][dx + 16] = 0xFF;
    }
  }
};
const DiscMasks kDiscMasks;

}  // namespace
}  // namespace rgbdo::simd
