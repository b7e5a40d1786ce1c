#include "rgbd_odometry/pipeline/match.hpp"

#include <cmath>
#include <cstring>

namespace rgbdo {
namespace {

// L2 nearest-two for float descriptors (SIFT, KAZE). Distances are squared L2 in
// float, bit-cast to uint32: for non-negative floats the bit patterns order like the values.
void nearest_two_l2(const cv::Mat& q, const cv::Mat& t, simd::NearestTwo* q_out, simd::NearestTwo* t_out) {
  for (int i = 0; i < q.rows; ++i) q_out[i] = {};
  for (int j = 0; j < t.rows; ++j) t_out[j] = {};
  for (int i = 0; i < q.rows; ++i) {
    const float* a = q.ptr<float>(i);
    for (int j = 0; j < t.rows; ++j) {
      const float* b = t.ptr<float>(j);
      float s = 0;
      for (int k = 0; k < q.cols; ++k) s += (a[k] - b[k]) * (a[k] - b[k]);
      std::uint32_t bits;
      std::memcpy(&bits, &s, sizeof bits);
      simd::keep_nearest_two(q_out[i], bits, j);  // the Hamming kernels' rule
      simd::keep_nearest_two(t_out[j], bits, i);
    }
  }
}

float as_distance(std::uint32_t d, bool binary) {
  if (binary) return static_cast<float>(d);
  float s;
  std::memcpy(&s, &d, sizeof s);
  return std::sqrt(s);
}

}  // namespace

bool passes_ratio_test(const simd::NearestTwo& n, double ratio) {
  if (n.best_index < 0) return false;
  if (n.second == UINT32_MAX) return true;
  return static_cast<double>(n.best) < ratio * static_cast<double>(n.second);
}

void SymmetricMatcher::match(const cv::Mat& prev, const cv::Mat& curr, std::vector<Match>& out) {
  out.clear();
  if (prev.empty() || curr.empty()) return;
  CV_Assert(prev.type() == curr.type() && prev.cols == curr.cols);
  prev_nn_.resize(static_cast<size_t>(prev.rows));
  curr_nn_.resize(static_cast<size_t>(curr.rows));
  const bool binary = prev.type() == CV_8UC1;
  if (binary) {
    hamming_(prev.data, prev.rows, prev.step, curr.data, curr.rows, curr.step, prev.cols,
                                     prev_nn_.data(), curr_nn_.data());
  } else {
    CV_Assert(prev.type() == CV_32FC1);
    nearest_two_l2(prev, curr, prev_nn_.data(), curr_nn_.data());
  }
  const auto passes = [&](const simd::NearestTwo& n) {
    if (binary) return passes_ratio_test(n, ratio_);
    if (n.best_index < 0) return false;
    if (n.second == UINT32_MAX) return true;
    return as_distance(n.best, false) < ratio_ * as_distance(n.second, false);
  };
  for (int i = 0; i < prev.rows; ++i) {
    const auto& forward = prev_nn_[static_cast<size_t>(i)];
    if (!passes(forward)) continue;
    const auto& backward = curr_nn_[static_cast<size_t>(forward.best_index)];
    if (backward.best_index != i || !passes(backward)) continue;
    out.push_back({i, forward.best_index, as_distance(forward.best, binary)});
  }
}

}  // namespace rgbdo
