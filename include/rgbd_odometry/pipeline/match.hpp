#pragma once
// Stage 2: candidate correspondences by the symmetric Lowe ratio test (Willis & Brink
// Sec. III-A): a pair (i, j) survives when j is i's nearest neighbour and passes the ratio
// test in the current frame, AND i is j's nearest neighbour and passes it in the previous.
#include <opencv2/core/mat.hpp>
#include <vector>

#include "rgbd_odometry/simd/kernels.hpp"

namespace rgbdo {

struct Match {
  int prev = 0;  // keypoint index in the previous frame
  int curr = 0;  // keypoint index in the current frame
  float distance = 0;
};

// The ratio test on one nearest-two record: best < ratio * second. A lone candidate
// (no second) passes; a tie (best == second) never does, as it is ambiguous.
bool passes_ratio_test(const simd::NearestTwo& n, double ratio);

class SymmetricMatcher {
 public:
  // Binds the active Hamming kernel (rgbd_odometry/simd/kernels.hpp) once, here.
  explicit SymmetricMatcher(double ratio)
      : ratio_(ratio), hamming_(simd::active_kernels().nearest_two_hamming), kernel_name_(simd::active_kernels().name) {}
  const char* kernel_name() const { return kernel_name_; }
  // Descriptors: CV_8U rows (Hamming) or CV_32F rows (L2). `out` is overwritten.
  void match(const cv::Mat& prev, const cv::Mat& curr, std::vector<Match>& out);

 private:
  double ratio_;
  simd::NearestTwoHammingFn hamming_;
  const char* kernel_name_;
  std::vector<simd::NearestTwo> prev_nn_, curr_nn_;  // kept across frames: no per-frame allocation
};

}  // namespace rgbdo
