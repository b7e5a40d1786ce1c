#pragma once
// Stage 2: candidate correspondences by the symmetric Lowe ratio test (Willis & Brink
// Sec. III-A): a pair (i, j) survives when j is i's nearest neighbour and passes the ratio
// test in the current frame, AND i is j's nearest neighbour and passes it in the previous.
#include <Eigen/Core>
#include <cmath>
#include <opencv2/core/mat.hpp>
#include <optional>
#include <span>
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
      : ratio_(ratio),
        hamming_(simd::active_kernels().nearest_two_hamming),
        hamming_rows_(simd::active_kernels().hamming_rows),
        kernel_name_(simd::active_kernels().name) {}
  const char* kernel_name() const { return kernel_name_; }
  // Sizes the buffers for frames of up to max_features keypoints: no allocation per pair after.
  void reserve(int max_features);
  // Descriptors: CV_8U rows (Hamming) or CV_32F rows (L2). `out` is overwritten.
  void match(const cv::Mat& prev, const cv::Mat& curr, std::vector<Match>& out);

  // The same test over the pairs a motion prior allows: previous keypoint i and current
  // keypoint j are compared only when j lies within `radius` (per axis) of where i is
  // predicted to appear, predicted[i] (NaN: no prediction, i takes part in no pair). Positions
  // in any one coordinate system (the pipeline: normalised image coordinates). Nearest and
  // second-nearest, and so the ratio test, are taken over those pairs only, in both
  // directions. Binary (CV_8U) descriptors; ties keep the lowest index, as in match().
  void match_within(const cv::Mat& prev, const cv::Mat& curr, std::span<const Eigen::Vector2d> predicted,
                    std::span<const Eigen::Vector2d> curr_positions, double radius, std::vector<Match>& out);

 private:
  // match_within's grid over the current keypoints' positions.
  struct Grid {
    double min_x = INFINITY, min_y = INFINITY, max_x = -INFINITY, max_y = -INFINITY;
    double cell_w = 0, cell_h = 0;
    int nx = 0, ny = 0;
    // nullopt when no position is finite.
    static std::optional<Grid> over(std::span<const Eigen::Vector2d> positions, double radius, int max_cells);
    int cell_x(double x) const;  // -1 below the grid (or NaN), up to nx beyond it
    int cell_y(double y) const;
  };
  void sort_by_cell(const Grid& grid, std::span<const Eigen::Vector2d> curr_positions);
  int window_candidates(const Grid& grid, const Eigen::Vector2d& p, double radius);

  // The symmetric ratio test over prev_nn_ / curr_nn_, as filled by either search.
  void keep_mutual(int n_prev, bool binary, std::vector<Match>& out) const;

  double ratio_;
  simd::NearestTwoHammingFn hamming_;
  simd::HammingRowsFn hamming_rows_;
  const char* kernel_name_;
  std::vector<simd::NearestTwo> prev_nn_, curr_nn_;  // kept across frames: no per-frame allocation
  // match_within's grid over the current keypoints: cell_start_ (per cell, row-major, and one
  // past the end) indexes by_cell_ (keypoint rows in cell order) and their positions.
  std::vector<int> cell_of_, cell_start_, by_cell_, candidates_;
  std::vector<Eigen::Vector2d> by_cell_position_;
  std::vector<std::uint32_t> distances_;
};

}  // namespace rgbdo
