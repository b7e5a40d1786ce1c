#pragma once
// Stage 1b: keypoints and descriptors, by name: our own GRID_ORB (grid_orb.hpp) or any
// OpenCV Feature2D (for comparison).
#include <memory>
#include <opencv2/core/mat.hpp>
#include <opencv2/features2d.hpp>

#include "rgbd_odometry/pipeline/pipeline_config.hpp"
#include "rgbd_odometry/pipeline/features.hpp"
#include "rgbd_odometry/pipeline/task_runner.hpp"

namespace rgbdo {

class GridOrbExtractor;

class FeatureDetector {
 public:
  // runner: where GRID_ORB may split its work (task_runner.hpp); null: all on the caller.
  explicit FeatureDetector(const FeatureConfig& config, TaskRunner* runner = nullptr);
  ~FeatureDetector();
  FeatureDetector(FeatureDetector&&) noexcept;
  FeatureDetector& operator=(FeatureDetector&&) noexcept;
  // Detects inside mask (CV_8UC1, 255 = allowed) and describes; out is overwritten.
  void detect(const cv::Mat& gray, const cv::Mat& mask, Features& out);
  bool binary_descriptors() const { return binary_; }

 private:
  FeatureConfig config_;
  TaskRunner* runner_;
  std::unique_ptr<GridOrbExtractor> grid_orb_;  // GRID_ORB: sized at the first frame
  cv::Ptr<cv::Feature2D> detector_;
  cv::Ptr<cv::Feature2D> descriptor_;  // same object as detector_ when the names agree
  bool binary_ = true;
};

}  // namespace rgbdo
