// Reference image kernels (rgbd_odometry/simd/image.hpp): the plain loops of their definitions.
#include <algorithm>
#include <cstring>

#include "rgbd_odometry/simd/image.hpp"

namespace rgbdo::simd {

RGBDO_BLEND_ROWS(blend_rows_scalar) {
  for (int i = 0; i < n; ++i) out[i] = static_cast<std::uint8_t>((r0[i] * (256 - w) + r1[i] * w + 128) >> 8);
}

RGBDO_RESAMPLE_ROW(resample_row_scalar) {
  for (int i = 0; i < n; ++i) {
    const ResampleGroup& g = groups[i / 8];
    const std::uint8_t* p = src + g.base + g.index[i % 8];
    const unsigned w = g.weight[i % 8];
    out[i] = static_cast<std::uint8_t>((p[0] * (256 - w) + p[1] * w + 128) >> 8);
  }
}

RGBDO_BOX5_ROW(box5_row_scalar) {
  for (int i = 0; i < n; ++i) {
    unsigned sum = 0;
    for (int dy = -2; dy <= 2; ++dy)
      for (int dx = -2; dx <= 2; ++dx) sum += centre[i + dy * stride + dx];
    out[i] = static_cast<std::uint16_t>(sum);
  }
}

RGBDO_SURFACE_MEAN5(surface_mean5_scalar) {
  for (int k = 0; k < n; ++k) {
    const float* c = depth + centre[k];
    float lane[4] = {0, 0, 0, 0}, column4 = 0;
    float lo = c[0], hi = c[0];
    for (std::ptrdiff_t dv = -2; dv <= 2; ++dv) {
      const float* row = c + dv * stride - 2;
      for (int i = 0; i < 4; ++i) lane[i] += row[i];
      column4 += row[4];
      for (int i = 0; i < 5; ++i) lo = std::min(lo, row[i]), hi = std::max(hi, row[i]);
    }
    const float sum = ((lane[0] + lane[1]) + (lane[2] + lane[3])) + column4;
    mean[k] = lo > 0 && hi - lo <= spread * c[0] ? sum * kSurfaceMeanScale : c[0];
  }
}

RGBDO_DEPTH_IN_RANGE_ROW(depth_in_range_row_scalar) {
  for (int i = 0; i < n; ++i) out[i] = depth[i] >= lo && depth[i] <= hi ? 255 : 0;
}

RGBDO_DISC_MOMENTS(disc_moments_scalar) {
  std::int32_t sx = 0, sy = 0;
  for (int dy = -kDiscRadius; dy <= kDiscRadius; ++dy) {
    const std::uint8_t* row = centre + dy * stride;
    const int hw = kDiscHalfWidth15[dy < 0 ? -dy : dy];
    std::int32_t row_sum = 0;
    for (int dx = -hw; dx <= hw; ++dx) {
      row_sum += row[dx];
      sx += dx * row[dx];
    }
    sy += dy * row_sum;
  }
  *m10 = sx;
  *m01 = sy;
}

RGBDO_COLOUR_TO_GRAY_ROW(colour_to_gray_row_scalar) {
  const std::uint32_t first = red_first ? kGrayRed : kGrayBlue, third = red_first ? kGrayBlue : kGrayRed;
  for (int i = 0; i < n; ++i) {
    const std::uint8_t* p = pixels + 3 * i;
    out[i] = static_cast<std::uint8_t>((p[0] * first + p[1] * kGrayGreen + p[2] * third + (1u << 14)) >> 15);
  }
}

RGBDO_DEPTH_TO_METRES_ROW(depth_to_metres_row_scalar) {
  for (int i = 0; i < n; ++i) out[i] = static_cast<float>(raw[i]) * metres_per_unit;
}

}  // namespace rgbdo::simd
