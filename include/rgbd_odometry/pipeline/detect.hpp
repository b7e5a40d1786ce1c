#pragma once
// Stage 1b: keypoints and descriptors from any OpenCV Feature2D chosen by name.
#include <opencv2/core/mat.hpp>
#include <opencv2/features2d.hpp>
#include <vector>

#include "rgbd_odometry/core/config.hpp"

namespace rgbdo {

struct Features {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;  // one row per keypoint; CV_8U (binary, Hamming) or CV_32F (L2)
};

class FeatureDetector {
 public:
  explicit FeatureDetector(const FeatureConfig& config);
  // Detects inside mask (CV_8UC1, 255 = allowed) and describes; out is overwritten.
  void detect(const cv::Mat& gray, const cv::Mat& mask, Features& out);
  bool binary_descriptors() const { return binary_; }

 private:
  cv::Ptr<cv::Feature2D> detector_;
  cv::Ptr<cv::Feature2D> descriptor_;  // same object as detector_ when the names agree
  bool binary_ = true;
};

}  // namespace rgbdo
