#pragma once
// One frame's keypoints and their descriptors, as every detector leaves them.
#include <opencv2/core/mat.hpp>
#include <opencv2/core/types.hpp>
#include <vector>

namespace rgbdo {

struct Features {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;  // one row per keypoint; CV_8U (binary, Hamming) or CV_32F (L2)
  // Where a detector that sizes its output once keeps the rows: `descriptors` is then a view
  // of its first rows, so a frame with fewer keypoints than the last allocates nothing.
  cv::Mat descriptor_storage;
};

}  // namespace rgbdo
