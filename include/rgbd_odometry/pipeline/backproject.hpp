#pragma once
// Stage 3: matched keypoints to 3-D points, X = x_n Z, Y = y_n Z (Willis & Brink eq. 1), with
// x_n, y_n the undistorted normalised coordinates from the calibrated intrinsics.
//
// Colour and depth of a PrimeSense sensor are captured at different instants (TUM fr1:
// up to 17 ms apart, the sign flipping from frame to frame, two colour frames sometimes
// sharing one depth image). Reading depth at a colour pixel then mixes two camera poses.
// With compensation on, each depth is carried to its colour frame's instant to first order:
//     Z(t_c) = Z(t_d) + (t_c - t_d) * (dZ/dt - grad Z . du/dt)
// where dZ/dt = -(v + w x P)_z is the depth rate of a static point seen by a camera moving
// with the motion prior (v, w), and du/dt is the match's own pixel velocity (the second term
// accounts for the surface sliding under the pixel on slanted surfaces).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <opencv2/core/types.hpp>
#include <vector>

#include "rgbd_odometry/pipeline/pipeline_config.hpp"
#include "rgbd_odometry/pipeline/match.hpp"

namespace rgbdo {

// Per-keypoint geometry of one frame, computed once per frame (each frame serves two pairs).
struct KeypointGeometry {
  std::vector<Eigen::Vector2d> normalized;      // undistorted (X/Z, Y/Z)
  std::vector<Eigen::Vector2d> pixel;           // distorted pixel position (the keypoint)
  std::vector<double> depth_m;                  // at the keypoint (its nearest pixel along the slope); 0: unusable (no reading, out of range, occlusion edge)
  std::vector<Eigen::Vector2d> depth_gradient;  // dZ/du, dZ/dv in metres per pixel
  void clear();
};

// Distorted pixel positions to undistorted normalised image coordinates (X/Z, Y/Z) by the
// camera's lens model, inverted by OpenCV's fixed-point steps run to convergence (its default
// 5 steps leave up to 0.13 px at the corners of TUM fr1's lens). `out` is resized.
void undistort_pixels_exactly(const CameraConfig& camera, const std::vector<cv::Point2f>& pixels,
                              std::vector<cv::Point2f>& out);

// The same, fast: the keypoints' rays (KeypointBackProjector) and the tracked ones'
// (pipeline/track.hpp). The inversion costs about 700 ARM instructions a point; with
// distortion it is run once, on a grid over the image, and a pixel inside the image is read by
// bilinear interpolation (test_backproject: within 0.008 px of the exact inversion on TUM fr1's
// lens). Without distortion it is the pinhole's division.
class PixelUndistorter {
 public:
  explicit PixelUndistorter(const CameraConfig& camera);
  // out[i] is the ray of pixels[i]; out is resized (no allocation within its capacity but for
  // pixels off the image, which are rare and inverted one by one).
  void undistort(const std::vector<cv::Point2f>& pixels, std::vector<cv::Point2f>& out) const;

 private:
  CameraConfig camera_;
  bool distorted_ = false;
  int grid_cols_ = 0, grid_rows_ = 0;  // nodes every kUndistortGridPx pixels from (0, 0)
  std::vector<cv::Point2f> grid_;      // row-major: the ray of each node
};

class KeypointBackProjector {
 public:
  KeypointBackProjector(const CameraConfig& camera, const DepthConfig& depth);
  void compute(const std::vector<cv::KeyPoint>& keypoints, const cv::Mat& depth_m, KeypointGeometry& out);

 private:
  PixelUndistorter undistorter_;
  DepthConfig depth_;
  std::vector<cv::Point2f> distorted_, undistorted_;
};

// Camera velocity in the camera frame, used to move depths between capture instants.
struct MotionPrior {
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular_velocity_radps = Eigen::Vector3d::Zero();
};

// The constant velocity that moves the camera by T_prev_curr over dt_s seconds.
MotionPrior motion_from(const Eigen::Isometry3d& T_prev_curr, double dt_s);

// A frame's capture times (RgbdFrame): intervals on the timeline, host time = t - host_lead_ns.
struct FrameTimes {
  std::int64_t t_colour_ns = 0;
  std::int64_t t_depth_ns = 0;
  std::int64_t host_lead_ns = 0;
  std::int64_t host_colour_ns() const { return t_colour_ns - host_lead_ns; }
};

// 3-D correspondences of a frame pair; index k of prev/curr belong together.
struct PointPairs {
  std::vector<Eigen::Vector3d> prev, curr;
  std::vector<int> match_index;  // into the matches the pairs were built from
  void clear();
  size_t size() const { return prev.size(); }
};

// A static point's depth seen at p (camera frame) read offset_s seconds away from the instant
// wanted, carried there to first order (see above): pixel_velocity is its image motion in px/s.
double depth_at_colour_instant(double z, const Eigen::Vector3d& p, const Eigen::Vector2d& depth_gradient,
                               const Eigen::Vector2d& pixel_velocity, double offset_s, const MotionPrior& motion);
// The image motion (px/s) of a static point at p while the camera moves with `motion`.
Eigen::Vector2d static_pixel_velocity(const Eigen::Vector3d& p, const MotionPrior& motion, double fx, double fy);

// Builds the pairs of all matches whose keypoints have usable depth in both frames.
// prior == nullptr: depth taken as measured (no timing compensation).
void build_point_pairs(const std::vector<Match>& matches, const KeypointGeometry& prev, const FrameTimes& prev_times,
                       const KeypointGeometry& curr, const FrameTimes& curr_times, const MotionPrior* prior,
                       PointPairs& out);

}  // namespace rgbdo
