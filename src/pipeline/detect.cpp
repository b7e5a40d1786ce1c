#include "rgbd_odometry/pipeline/detect.hpp"

#include <algorithm>
#include <stdexcept>

#include "rgbd_odometry/pipeline/grid_orb.hpp"

namespace rgbdo {
namespace {

cv::Ptr<cv::Feature2D> create_feature2d(const std::string& name, const FeatureConfig& c) {
  const int max_features = c.max_features;
  if (name == "ORB")
    return cv::ORB::create(max_features, static_cast<float>(c.orb_scale_factor), c.orb_levels, 31, 0, 2,
                           cv::ORB::HARRIS_SCORE, 31, c.fast_threshold);
  if (name == "AKAZE") return cv::AKAZE::create();
  if (name == "BRISK") return cv::BRISK::create();
  if (name == "SIFT") return cv::SIFT::create(max_features);
  if (name == "KAZE") return cv::KAZE::create();
  if (name == "FAST") return cv::FastFeatureDetector::create();
  if (name == "GFTT") return cv::GFTTDetector::create(max_features);
  if (name == "AGAST") return cv::AgastFeatureDetector::create();
  throw std::invalid_argument("unknown OpenCV Feature2D '" + name + "'");
}

}  // namespace

FeatureDetector::FeatureDetector(const FeatureConfig& config, TaskRunner* runner) : config_(config), runner_(runner) {
  if (config.detector == kGridOrb) return;  // its own descriptors (validate() insists)
  detector_ = create_feature2d(config.detector, config);
  descriptor_ = config.descriptor == config.detector ? detector_ : create_feature2d(config.descriptor, config);
  binary_ = descriptor_->defaultNorm() == cv::NORM_HAMMING;
}

FeatureDetector::~FeatureDetector() = default;
FeatureDetector::FeatureDetector(FeatureDetector&&) noexcept = default;
FeatureDetector& FeatureDetector::operator=(FeatureDetector&&) noexcept = default;

void FeatureDetector::detect(const cv::Mat& gray, const cv::Mat& mask, Features& out) {
  if (config_.detector == kGridOrb) {
    if (!grid_orb_ || !grid_orb_->sized_for(gray.cols, gray.rows))
      grid_orb_ = std::make_unique<GridOrbExtractor>(config_, gray.cols, gray.rows, runner_);
    grid_orb_->detect(gray, mask, out);
    return;
  }
  out.keypoints.clear();
  if (config_.detector == "ORB" && detector_ == descriptor_) {
    detector_->detectAndCompute(gray, mask, out.keypoints, out.descriptors);  // ORB keeps its own cap
    return;
  }
  // Every other detector finds as many as it likes (FAST: ~2,700 on a textured frame): the
  // strongest max_features are kept, so that matching's cost has the configured bound.
  detector_->detect(gray, out.keypoints, mask);
  const auto cap = static_cast<size_t>(config_.max_features);
  if (out.keypoints.size() > cap) {
    cv::KeyPointsFilter::retainBest(out.keypoints, config_.max_features);
    out.keypoints.resize(std::min(out.keypoints.size(), cap));  // retainBest keeps ties at the cut
  }
  descriptor_->compute(gray, out.keypoints, out.descriptors);
}

}  // namespace rgbdo
