#include "rgbd_odometry/pipeline/backproject.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>

#include "rgbd_odometry/core/geometry.hpp"

namespace rgbdo {
namespace {

constexpr int kEdgeRadiusPx = 2;  // 5x5: Kinect-v1 depth is block-matched over ~9 px windows
// PixelUndistorter's grid: nodes this many pixels apart (test_backproject measures what it leaves).
constexpr int kUndistortGridPx = 4;
// The lens model's inversion, converged to 0.001 px by 20 steps over TUM fr1's whole image.
constexpr int kLensInversionSteps = 50;

}  // namespace

void KeypointGeometry::clear() {
  normalized.clear();
  pixel.clear();
  depth_m.clear();
  depth_gradient.clear();
}

void PointPairs::clear() {
  prev.clear();
  curr.clear();
  match_index.clear();
}

void undistort_pixels_exactly(const CameraConfig& camera, const std::vector<cv::Point2f>& pixels,
                              std::vector<cv::Point2f>& out) {
  if (pixels.empty()) {
    out.clear();
    return;
  }
  const cv::Mat K = (cv::Mat_<double>(3, 3) << camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
  const cv::Mat distortion(1, 5, CV_64F, const_cast<double*>(camera.distortion.data()));
  cv::undistortPoints(pixels, out, K, distortion, cv::noArray(), cv::noArray(),
                      cv::TermCriteria(cv::TermCriteria::COUNT, kLensInversionSteps, 0));
}

PixelUndistorter::PixelUndistorter(const CameraConfig& camera)
    : camera_(camera),
      distorted_(std::any_of(camera.distortion.begin(), camera.distortion.end(), [](double k) { return k != 0; })) {
  if (!distorted_) return;
  // Nodes reach the last pixel row and column (and at most one step beyond).
  grid_cols_ = (std::max(camera.width, 2) - 1 + kUndistortGridPx - 1) / kUndistortGridPx + 1;
  grid_rows_ = (std::max(camera.height, 2) - 1 + kUndistortGridPx - 1) / kUndistortGridPx + 1;
  std::vector<cv::Point2f> nodes;
  nodes.reserve(static_cast<size_t>(grid_cols_) * static_cast<size_t>(grid_rows_));
  for (int j = 0; j < grid_rows_; ++j)
    for (int i = 0; i < grid_cols_; ++i)
      nodes.emplace_back(static_cast<float>(i * kUndistortGridPx), static_cast<float>(j * kUndistortGridPx));
  undistort_pixels_exactly(camera, nodes, grid_);
}

void PixelUndistorter::undistort(const std::vector<cv::Point2f>& pixels, std::vector<cv::Point2f>& out) const {
  out.resize(pixels.size());
  if (!distorted_) {
    const auto fx = static_cast<float>(camera_.fx), fy = static_cast<float>(camera_.fy);
    const auto cx = static_cast<float>(camera_.cx), cy = static_cast<float>(camera_.cy);
    for (size_t k = 0; k < pixels.size(); ++k) out[k] = {(pixels[k].x - cx) / fx, (pixels[k].y - cy) / fy};
    return;
  }
  constexpr float kInverseStep = 1.0f / kUndistortGridPx;
  const auto last_col = static_cast<float>(grid_cols_ - 1), last_row = static_cast<float>(grid_rows_ - 1);
  for (size_t k = 0; k < pixels.size(); ++k) {
    const float gx = pixels[k].x * kInverseStep, gy = pixels[k].y * kInverseStep;
    if (!(gx >= 0 && gy >= 0 && gx <= last_col && gy <= last_row)) {  // off the image (or NaN)
      std::vector<cv::Point2f> ray;
      undistort_pixels_exactly(camera_, {pixels[k]}, ray);
      out[k] = ray[0];
      continue;
    }
    const int i = std::min(static_cast<int>(gx), grid_cols_ - 2), j = std::min(static_cast<int>(gy), grid_rows_ - 2);
    const float a = gx - static_cast<float>(i), b = gy - static_cast<float>(j);
    const cv::Point2f* n = grid_.data() + static_cast<size_t>(j) * static_cast<size_t>(grid_cols_) + i;
    const cv::Point2f top = n[0] + a * (n[1] - n[0]);
    const cv::Point2f bottom = n[grid_cols_] + a * (n[grid_cols_ + 1] - n[grid_cols_]);
    out[k] = top + b * (bottom - top);
  }
}

KeypointBackProjector::KeypointBackProjector(const CameraConfig& camera, const DepthConfig& depth)
    : undistorter_(camera), depth_(depth) {}

void KeypointBackProjector::compute(const std::vector<cv::KeyPoint>& keypoints, const cv::Mat& depth_m,
                                    KeypointGeometry& out) {
  CV_Assert(depth_m.type() == CV_32FC1);
  out.clear();
  const size_t n = keypoints.size();
  distorted_.resize(n);
  for (size_t i = 0; i < n; ++i) distorted_[i] = keypoints[i].pt;
  undistorter_.undistort(distorted_, undistorted_);

  const int r = kEdgeRadiusPx;
  for (size_t i = 0; i < n; ++i) {
    out.normalized.emplace_back(undistorted_[i].x, undistorted_[i].y);
    out.pixel.emplace_back(distorted_[i].x, distorted_[i].y);
    // Where the depth image shows what the colour shows at the keypoint (its registration).
    const Eigen::Vector2d at(distorted_[i].x - depth_.registration_x_px, distorted_[i].y - depth_.registration_y_px);
    const int u = static_cast<int>(std::lround(at.x()));
    const int v = static_cast<int>(std::lround(at.y()));
    double z = 0;
    Eigen::Vector2d gradient = Eigen::Vector2d::Zero();
    if (u >= r && v >= r && u < depth_m.cols - r && v < depth_m.rows - r) {
      const double centre = depth_m.at<float>(v, u);
      float lo = depth_m.at<float>(v, u), hi = lo;
      for (int dv = -r; dv <= r; ++dv) {
        const float* row = depth_m.ptr<float>(v + dv);
        for (int du = -r; du <= r; ++du) {
          lo = std::min(lo, row[u + du]);
          hi = std::max(hi, row[u + du]);
        }
      }
      // All neighbours valid and no depth step: the keypoint is not on an occlusion edge,
      // where its colour and its depth may belong to different surfaces.
      if (centre >= depth_.min_m && centre <= depth_.max_m && lo > 0 &&
          (hi - lo) <= depth_.edge_max_relative_step * centre) {
        z = centre;
        gradient.x() = (depth_m.at<float>(v, u + r) - depth_m.at<float>(v, u - r)) / (2.0 * r);
        gradient.y() = (depth_m.at<float>(v + r, u) - depth_m.at<float>(v - r, u)) / (2.0 * r);
        // Read at the nearest pixel, carried along the slope to the keypoint's own position,
        // a fraction of a pixel away (more for a coarse pyramid level's keypoint).
        z += gradient.dot(at - Eigen::Vector2d(u, v));
      }
    }
    out.depth_m.push_back(z);
    out.depth_gradient.push_back(gradient);
  }
}

MotionPrior motion_from(const Eigen::Isometry3d& T_prev_curr, double dt_s) {
  MotionPrior m;
  m.velocity_mps = T_prev_curr.translation() / dt_s;
  m.angular_velocity_radps = rotation_vector(T_prev_curr.linear()) / dt_s;
  return m;
}

double depth_at_colour_instant(double z, const Eigen::Vector3d& p, const Eigen::Vector2d& depth_gradient,
                               const Eigen::Vector2d& pixel_velocity, double offset_s, const MotionPrior& motion) {
  const double z_rate = -(motion.velocity_mps + motion.angular_velocity_radps.cross(p)).z();
  return z + offset_s * (z_rate - depth_gradient.dot(pixel_velocity));
}

Eigen::Vector2d static_pixel_velocity(const Eigen::Vector3d& p, const MotionPrior& motion, double fx, double fy) {
  // In the moving camera a static point moves by -(v + w x p); its projection x/z, y/z with it.
  const Eigen::Vector3d dp = -(motion.velocity_mps + motion.angular_velocity_radps.cross(p));
  const double z2 = p.z() * p.z();
  return {fx * (dp.x() * p.z() - p.x() * dp.z()) / z2, fy * (dp.y() * p.z() - p.y() * dp.z()) / z2};
}

void build_point_pairs(const std::vector<Match>& matches, const KeypointGeometry& prev, const FrameTimes& prev_times,
                       const KeypointGeometry& curr, const FrameTimes& curr_times, const MotionPrior* prior,
                       PointPairs& out) {
  out.clear();
  const double dt_colour = static_cast<double>(curr_times.t_colour_ns - prev_times.t_colour_ns) * 1e-9;
  const double prev_offset = static_cast<double>(prev_times.t_colour_ns - prev_times.t_depth_ns) * 1e-9;
  const double curr_offset = static_cast<double>(curr_times.t_colour_ns - curr_times.t_depth_ns) * 1e-9;
  const bool compensate = prior != nullptr && dt_colour > 0;

  const auto depth_at_colour_time = [&](double z, const Eigen::Vector2d& xn, const Eigen::Vector2d& gradient,
                                        const Eigen::Vector2d& pixel_velocity, double offset) {
    if (!compensate || offset == 0) return z;
    return depth_at_colour_instant(z, Eigen::Vector3d(xn.x() * z, xn.y() * z, z), gradient, pixel_velocity, offset,
                                   *prior);
  };

  for (size_t k = 0; k < matches.size(); ++k) {
    const auto i = static_cast<size_t>(matches[k].prev);
    const auto j = static_cast<size_t>(matches[k].curr);
    if (prev.depth_m[i] <= 0 || curr.depth_m[j] <= 0) continue;
    const Eigen::Vector2d pixel_velocity =
        compensate ? Eigen::Vector2d((curr.pixel[j] - prev.pixel[i]) / dt_colour) : Eigen::Vector2d::Zero();
    const double zp = depth_at_colour_time(prev.depth_m[i], prev.normalized[i], prev.depth_gradient[i],
                                           pixel_velocity, prev_offset);
    const double zc = depth_at_colour_time(curr.depth_m[j], curr.normalized[j], curr.depth_gradient[j],
                                           pixel_velocity, curr_offset);
    out.prev.emplace_back(prev.normalized[i].x() * zp, prev.normalized[i].y() * zp, zp);
    out.curr.emplace_back(curr.normalized[j].x() * zc, curr.normalized[j].y() * zc, zc);
    out.match_index.push_back(static_cast<int>(k));
  }
}

}  // namespace rgbdo
