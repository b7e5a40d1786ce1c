#pragma once
// How well the keypoints are localised, pyramid level by level, learnt from the data without
// ground truth: each pair's inliers, the previous frame's point carried by the fitted motion
// into the current image, land off their matched keypoint by both keypoints' localisation
// errors (a depth error moves the point along its ray, which the small baseline between two
// frames hardly shows: 0.02 px for the Kinect's 1.4 mm at 1 m over 2 cm). Where both keypoints
// are of one level, the 2-D residual's length is Rayleigh-distributed with scale sqrt(2) sigma:
// its median is 1.665 sigma.
//
// Measured (medians over a sequence): the Kinect on fr1_xyz 0.50, 0.48, 0.51, 0.57, 0.64, 0.72,
// 0.87, 1.05 px at levels 0-7, where the corner-quantisation law (0.289 px x 1.2^level) says
// 0.29 ... 1.04: its blurred, noisy images put a floor of ~0.5 px under the fine levels. The
// rendered ICL-NUIM images: 0.32, 0.34, 0.39, 0.40, 0.40, 0.54, 0.66, 0.51 px.
//
// Each level starts at the law (covariance.pixel_sigma_px x features.orb_scale_factor^level);
// a pair with at least kMinResiduals residuals at a level gives a reading, taken in by
// learnt_constant.hpp's rule: the first ten readings averaged with the prior (counted as one):
// the Kinect's fine levels are at twice the law, which 10 % a pair would take 8 pairs to
// reach. After them each reading moves the estimate by kRate of the difference (a reading from
// a few dozen residuals is noisy by ~10 %), at most kRate of itself. It stays within
// [kMinSigma_px, kMaxSigma_px].
// Allocation-free after construction.
#include <array>
#include <vector>

#include "rgbd_odometry/pipeline/learnt_constant.hpp"

namespace rgbdo {

class KeypointSigmaEstimate {
 public:
  static constexpr int kMaxLevels = 16;  // features.orb_levels' bound
  static constexpr double kRate = 0.1;
  static constexpr int kMinResiduals = 8;
  static constexpr double kMinSigma_px = 0.05, kMaxSigma_px = 5.0;

  KeypointSigmaEstimate(double pixel_sigma_px, double level_scale, int levels, int capacity);

  // One inlier of the pair at hand whose two keypoints are of `level`: its reprojection
  // residual's length in pixels. Other levels and non-finite residuals are ignored.
  void add(int level, double residual_px);
  // The pair's readings taken in; the residuals are forgotten.
  void update();

  double sigma_px(int level) const;  // clamped to the levels there are
  int levels() const { return levels_; }

 private:
  int levels_;
  std::vector<LearntConstant> sigma_;  // one per level
  std::array<std::vector<float>, kMaxLevels> residuals_;
};

}  // namespace rgbdo
