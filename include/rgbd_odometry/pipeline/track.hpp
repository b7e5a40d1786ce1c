#pragma once
// Sub-pixel tracking of matched keypoints. A keypoint is a FAST corner on its pyramid level's
// integer grid: off by a uniform +-0.5 level pixel, 0.29 px at level 0 and 1.2 times more per
// level, and a corner is not a sub-pixel-stable point (OpenCV's cornerSubPix on each frame
// alone did not help). What a motion needs is not where each corner is but where the
// previous frame's point went: the previous keypoint's 8x8 patch of the full-resolution image
// is found again in the current image, started at the matched keypoint, by Lucas-Kanade
// (translation only, the template's gradients fixed: the inverse-compositional form of Baker
// & Matthews 2004), in fixed point on the kernels of simd/track.hpp. The current keypoint then
// stands where the previous keypoint's point is seen, to a few hundredths of a pixel on a
// sharp image; its depth moves with it along the depth map's slope.
#include <span>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "rgbd_odometry/pipeline/pipeline_config.hpp"
#include "rgbd_odometry/pipeline/backproject.hpp"
#include "rgbd_odometry/pipeline/match.hpp"
#include "rgbd_odometry/simd/kernels.hpp"

namespace rgbdo {

// Whether a pipeline so configured tracks its matched keypoints: matching.subpixel_tracking,
// never under the paper's covariance model (its pipeline).
inline bool tracks_keypoints(const PipelineConfig& config) {
  return config.matching.subpixel_tracking && config.covariance.model != "paper";
}

// Where one patch went.
struct PatchTrack {
  bool ok = false;
  Eigen::Vector2d position = Eigen::Vector2d::Zero();  // in the current image, pixels
  int iterations = 0;
};

class SubpixelTracker {
 public:
  // A track may move its keypoint at most max_shift_px x scale_factor^level from where the
  // detector put it: further, the patch has found something else.
  SubpixelTracker(const CameraConfig& camera, double scale_factor, int max_keypoints, double max_shift_px = 1.0);

  // The patch of `prev` centred at `from`, found in `curr` starting at `start`. Not ok when
  // either patch leaves the image, the patch has no texture in some direction, or the track
  // moves further than max_shift from `start`.
  PatchTrack track_patch(const cv::Mat& prev, const Eigen::Vector2d& from, const cv::Mat& curr,
                         const Eigen::Vector2d& start, double max_shift) const;

  // `out` becomes curr's geometry with the current keypoint of every matches[which[k]] moved to
  // where its previous keypoint's patch lies (pixel, its undistorted ray, its depth along the
  // depth map's slope). Keypoints whose track fails keep the detector's position. Returns how
  // many moved. Reuses out's buffers.
  int track(const cv::Mat& prev_gray, const KeypointGeometry& prev, const cv::Mat& curr_gray,
            const KeypointGeometry& curr, const std::vector<cv::KeyPoint>& curr_keypoints,
            const std::vector<Match>& matches, std::span<const int> which, KeypointGeometry& out);

 private:
  PixelUndistorter undistorter_;
  double scale_factor_;
  double max_shift_px_;
  simd::TrackSample8Fn sample8_;
  simd::TrackSums8x8Fn sums8x8_;
  std::vector<cv::Point2f> moved_, undistorted_;
  std::vector<int> moved_keypoint_;
};

}  // namespace rgbdo
