#include "rgbd_odometry/pipeline/frame_convert.hpp"

#include "rgbd_odometry/simd/kernels.hpp"

namespace rgbdo {

void colour_to_gray(const cv::Mat& colour, bool red_first, cv::Mat& gray) {
  CV_Assert(colour.type() == CV_8UC3);
  gray.create(colour.size(), CV_8UC1);  // in place would overwrite what is still to be read
  CV_Assert(gray.data != colour.data);
  const simd::ColourToGrayRowFn convert = simd::active_kernels().colour_to_gray_row;
  for (int y = 0; y < colour.rows; ++y) convert(colour.ptr<std::uint8_t>(y), colour.cols, red_first, gray.ptr<std::uint8_t>(y));
}

void depth_to_metres(const cv::Mat& raw, double metres_per_unit, cv::Mat& metres) {
  CV_Assert(raw.type() == CV_16UC1);
  metres.create(raw.size(), CV_32FC1);
  const simd::DepthToMetresRowFn convert = simd::active_kernels().depth_to_metres_row;
  const auto scale = static_cast<float>(metres_per_unit);
  for (int y = 0; y < raw.rows; ++y) convert(raw.ptr<std::uint16_t>(y), raw.cols, scale, metres.ptr<float>(y));
}

}  // namespace rgbdo
