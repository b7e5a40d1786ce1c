#include "rgbd_odometry/pipeline/mask.hpp"

#include <algorithm>
#include <cstring>

#include "rgbd_odometry/simd/kernels.hpp"

namespace rgbdo {

void build_feature_mask(const cv::Mat& depth_m, const DepthConfig& depth, int border_px, cv::Mat& mask) {
  CV_Assert(depth_m.type() == CV_32FC1);
  mask.create(depth_m.size(), CV_8UC1);
  const int w = mask.cols, h = mask.rows;
  const int b = std::clamp(std::min({border_px, w / 2, h / 2}), 0, w);
  // The periphery zero, the inside by the range test (cv::inRange's rule, our SIMD kernel:
  // Debian's armhf OpenCV has no NEON).
  const simd::DepthInRangeRowFn in_range = simd::active_kernels().depth_in_range_row;
  const auto lo = static_cast<float>(depth.min_m), hi = static_cast<float>(depth.max_m);
  for (int y = 0; y < h; ++y) {
    std::uint8_t* row = mask.ptr<std::uint8_t>(y);
    if (y < b || y >= h - b) {
      std::memset(row, 0, static_cast<size_t>(w));
      continue;
    }
    std::memset(row, 0, static_cast<size_t>(b));
    in_range(depth_m.ptr<float>(y) + b, w - 2 * b, lo, hi, row + b);
    std::memset(row + w - b, 0, static_cast<size_t>(b));
  }
}

bool mask_is_empty(const cv::Mat& mask) {
  for (int y = 0; y < mask.rows; ++y) {
    const std::uint8_t* row = mask.ptr<std::uint8_t>(y);
    if (std::any_of(row, row + mask.cols, [](std::uint8_t v) { return v != 0; })) return false;
  }
  return true;
}

}  // namespace rgbdo
