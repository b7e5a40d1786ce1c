#pragma once
// Stage 1a: which pixels may carry a feature. The periphery (strongest lens distortion,
// ORB's own border) and pixels without a usable depth reading are excluded before
// detection, so no detector effort is spent where no 3-D point can be made.
#include <opencv2/core/mat.hpp>

#include "rgbd_odometry/pipeline/pipeline_config.hpp"

namespace rgbdo {

// Writes a CV_8UC1 mask (255 = usable) of depth_m's size into mask; reuses its buffer.
void build_feature_mask(const cv::Mat& depth_m, const DepthConfig& depth, int border_px, cv::Mat& mask);

// Whether no pixel is usable; stops at the first that is (cv::countNonZero reads them all).
bool mask_is_empty(const cv::Mat& mask);

}  // namespace rgbdo
