#include "rgbd_odometry/pipeline/track.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

namespace rgbdo {
namespace {

constexpr int kPatch = 8;         // the kernels' patch width
constexpr int kMaxIterations = 10;
constexpr double kConverged = 0.01;  // px: a step this small ends the iterations
// The patch must be textured in both directions: the smaller eigenvalue of its gradients'
// second-moment matrix, per pixel, at least this (grey levels per pixel, squared). A blank
// wall, or a straight edge across the patch, gives little more than its noise there.
constexpr double kMinTexture = 4.0;

// The top-left pixel and the bilinear weights of a sample grid starting at (x, y).
struct SampleGrid {
  int x = 0, y = 0;
  std::array<std::int32_t, 4> w{};
};

// Each fraction of a pixel is rounded to 1/128 (0.008 px, a fifth of the tracker's own error)
// and the weights are products of the two: never negative and summing to 2^14 exactly. (Weights
// rounded one by one, as OpenCV's, can sum past 2^14 and leave the last one at -1.)
SampleGrid grid_at(double x, double y) {
  SampleGrid g;
  const double fx = std::floor(x), fy = std::floor(y);
  g.x = static_cast<int>(fx);
  g.y = static_cast<int>(fy);
  constexpr int one = 1 << (simd::kTrackWeightBits / 2);
  auto a = static_cast<std::int32_t>(std::lround((x - fx) * one));
  auto b = static_cast<std::int32_t>(std::lround((y - fy) * one));
  // A fraction rounded up to a whole pixel: the next pixel, weighted alone.
  if (a == one) {
    ++g.x;
    a = 0;
  }
  if (b == one) {
    ++g.y;
    b = 0;
  }
  g.w = {(one - a) * (one - b), a * (one - b), (one - a) * b, a * b};
  return g;
}

// Whether `rows` rows of `cols` samples from g stay in the image (each reads one more pixel
// to the right and below).
bool inside(const cv::Mat& image, const SampleGrid& g, int cols, int rows) {
  return g.x >= 0 && g.y >= 0 && g.x + cols + 1 <= image.cols && g.y + rows + 1 <= image.rows;
}

}  // namespace

SubpixelTracker::SubpixelTracker(const CameraConfig& camera, double scale_factor, int max_keypoints,
                                 double max_shift_px)
    : undistorter_(camera),
      scale_factor_(scale_factor),
      max_shift_px_(max_shift_px),
      sample8_(simd::active_kernels().track_sample8),
      sums8x8_(simd::active_kernels().track_sums8x8) {
  const auto capacity = static_cast<size_t>(max_keypoints);
  moved_.reserve(capacity);
  undistorted_.reserve(capacity);
  moved_keypoint_.reserve(capacity);
}

PatchTrack SubpixelTracker::track_patch(const cv::Mat& prev, const Eigen::Vector2d& from, const cv::Mat& curr,
                                        const Eigen::Vector2d& start, double max_shift) const {
  PatchTrack t;
  // The template: samples at from + (i - 3.5), i = 0..7, with a one-sample border for its
  // gradients: a 10x10 grid from from - 4.5, sampled as two 8-wide blocks (columns 0-7, 2-9).
  const SampleGrid g = grid_at(from.x() - 4.5, from.y() - 4.5);
  if (!inside(prev, g, kPatch + 2, kPatch + 2)) return t;
  std::array<std::int16_t, 10 * kPatch> left, right;
  const std::uint8_t* top_left = prev.ptr<std::uint8_t>(g.y) + g.x;
  sample8_(top_left, static_cast<std::ptrdiff_t>(prev.step), kPatch + 2, g.w.data(), left.data());
  sample8_(top_left + 2, static_cast<std::ptrdiff_t>(prev.step), kPatch + 2, g.w.data(), right.data());
  const auto at = [&](int r, int c) { return c < kPatch ? left[r * kPatch + c] : right[r * kPatch + c - 2]; };
  std::array<std::int16_t, kPatch * kPatch> templ, gx, gy;
  std::int64_t gxx = 0, gxy = 0, gyy = 0;
  for (int r = 0; r < kPatch; ++r)
    for (int c = 0; c < kPatch; ++c) {
      const int k = r * kPatch + c;
      templ[k] = at(r + 1, c + 1);
      gx[k] = static_cast<std::int16_t>(at(r + 1, c + 2) - at(r + 1, c));
      gy[k] = static_cast<std::int16_t>(at(r + 2, c + 1) - at(r, c + 1));
      gxx += gx[k] * gx[k];
      gxy += gx[k] * gy[k];
      gyy += gy[k] * gy[k];
    }
  // gx is twice the slope in sample units (1/8 grey level): 16 times grey levels per pixel.
  const double xx = static_cast<double>(gxx), xy = static_cast<double>(gxy), yy = static_cast<double>(gyy);
  const double min_eigen = 0.5 * (xx + yy - std::sqrt((xx - yy) * (xx - yy) + 4 * xy * xy));
  constexpr double per_pixel = 16.0 * 16.0 * kPatch * kPatch;
  if (!(min_eigen >= kMinTexture * per_pixel)) return t;
  const double det = xx * yy - xy * xy;

  Eigen::Vector2d c = start;
  std::array<std::int16_t, kPatch * kPatch> sampled;
  std::array<std::int32_t, 3> sums{};
  for (t.iterations = 1; t.iterations <= kMaxIterations; ++t.iterations) {
    const SampleGrid h = grid_at(c.x() - 3.5, c.y() - 3.5);
    if (!inside(curr, h, kPatch, kPatch)) return t;
    sample8_(curr.ptr<std::uint8_t>(h.y) + h.x, static_cast<std::ptrdiff_t>(curr.step), kPatch, h.w.data(),
             sampled.data());
    sums8x8_(sampled.data(), templ.data(), gx.data(), gy.data(), sums.data());
    // Gauss-Newton on sum (S(c + step) - T)^2 with T's slopes g = gx / 2:
    // step = -(sum g g^T)^-1 sum g d = -2 (sum gx gx^T)^-1 sum gx d.
    const double bx = sums[0], by = sums[1];
    const Eigen::Vector2d step(-2.0 * (yy * bx - xy * by) / det, -2.0 * (xx * by - xy * bx) / det);
    c += step;
    if ((c - start).norm() > max_shift) return t;
    if (step.norm() < kConverged) break;
  }
  t.ok = true;
  t.position = c;
  return t;
}

int SubpixelTracker::track(const cv::Mat& prev_gray, const KeypointGeometry& prev, const cv::Mat& curr_gray,
                           const KeypointGeometry& curr, const std::vector<cv::KeyPoint>& curr_keypoints,
                           const std::vector<Match>& matches, std::span<const int> which, KeypointGeometry& out) {
  out = curr;  // reuses out's buffers
  moved_.clear();
  moved_keypoint_.clear();
  if (prev_gray.type() != CV_8UC1 || curr_gray.type() != CV_8UC1) return 0;
  for (int w : which) {
    const Match& m = matches[static_cast<size_t>(w)];
    const auto i = static_cast<size_t>(m.prev), j = static_cast<size_t>(m.curr);
    const double max_shift = max_shift_px_ * std::pow(scale_factor_, std::max(0, curr_keypoints[j].octave));
    const PatchTrack t = track_patch(prev_gray, prev.pixel[i], curr_gray, curr.pixel[j], max_shift);
    if (!t.ok) continue;
    out.pixel[j] = t.position;
    // The keypoint's depth (backproject.cpp) carried to the tracked position along the depth
    // map's slope.
    if (out.depth_m[j] > 0) out.depth_m[j] += curr.depth_gradient[j].dot(t.position - curr.pixel[j]);
    moved_.emplace_back(static_cast<float>(t.position.x()), static_cast<float>(t.position.y()));
    moved_keypoint_.push_back(static_cast<int>(j));
  }
  if (moved_.empty()) return 0;
  undistorter_.undistort(moved_, undistorted_);
  for (size_t k = 0; k < moved_.size(); ++k)
    out.normalized[static_cast<size_t>(moved_keypoint_[k])] = {undistorted_[k].x, undistorted_[k].y};
  return static_cast<int>(moved_.size());
}

}  // namespace rgbdo
