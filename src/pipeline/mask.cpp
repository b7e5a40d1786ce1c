#include "rgbd_odometry/pipeline/mask.hpp"

#include <opencv2/imgproc.hpp>

namespace rgbdo {

void build_feature_mask(const cv::Mat& depth_m, const DepthConfig& depth, int border_px, cv::Mat& mask) {
  CV_Assert(depth_m.type() == CV_32FC1);
  cv::inRange(depth_m, depth.min_m, depth.max_m, mask);
  if (border_px <= 0) return;
  const int w = mask.cols, h = mask.rows;
  const int b = std::min({border_px, w / 2, h / 2});
  mask.rowRange(0, b).setTo(0);
  mask.rowRange(h - b, h).setTo(0);
  mask.colRange(0, b).setTo(0);
  mask.colRange(w - b, w).setTo(0);
}

}  // namespace rgbdo
