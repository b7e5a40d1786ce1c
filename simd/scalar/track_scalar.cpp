// Reference kernels of the sub-pixel tracker (rgbd_odometry/simd/track.hpp).
#include "rgbd_odometry/simd/track.hpp"

namespace rgbdo::simd {

void track_sample8_scalar(const std::uint8_t* top_left, std::ptrdiff_t stride, int rows, const std::int32_t* w,
                          std::int16_t* out) {
  constexpr int shift = kTrackWeightBits - kTrackValueBits;
  for (int r = 0; r < rows; ++r) {
    const std::uint8_t* p = top_left + r * stride;
    const std::uint8_t* q = p + stride;
    for (int i = 0; i < 8; ++i) {
      const std::int32_t v = w[0] * p[i] + w[1] * p[i + 1] + w[2] * q[i] + w[3] * q[i + 1];
      out[r * 8 + i] = static_cast<std::int16_t>((v + (1 << (shift - 1))) >> shift);
    }
  }
}

void track_sums8x8_scalar(const std::int16_t* sampled, const std::int16_t* templ, const std::int16_t* gx,
                          const std::int16_t* gy, std::int32_t* sums) {
  std::int32_t sx = 0, sy = 0, sd = 0;
  for (int k = 0; k < 64; ++k) {
    const std::int32_t d = sampled[k] - templ[k];
    sx += d * gx[k];
    sy += d * gy[k];
    sd += d * d;
  }
  sums[0] = sx;
  sums[1] = sy;
  sums[2] = sd;
}

}  // namespace rgbdo::simd
