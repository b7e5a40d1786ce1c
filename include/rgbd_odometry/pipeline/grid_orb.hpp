#pragma once
// Stage 1b, our own: ORB-class keypoints and 256-bit steered binary descriptors, spread over
// the image, with no heap allocation per frame after the first (features.detector: GRID_ORB).
// OpenCV's ORB on the Odroid runs Debian's armhf build, which has no NEON
// (bench/MEASUREMENTS.md#arm-cost-model); this extractor's hot loops are ours, so they can be.
//
//   pyramid       levels 1.. downscaled from the previous level by scale_factor, bilinear in
//                 fixed point (weights in 1/256), pixel centres aligned: a vertical pass over
//                 whole rows, then a horizontal one gathering eight outputs at a time (SIMD
//                 kernels, simd/image.hpp)
//   FAST-9        segment test on each level at fast_threshold; on a level short of corners
//                 (blur, bare scenes) a grid cell that finds none at it looks again at
//                 kFastLowThreshold (ORB-SLAM's fallback), so a textureless cell still yields
//                 its best corner. Score: the summed excess of
//                 the circle's differences over the threshold; 3x3 non-maximum suppression
//   spread        each level's budget (ORB-SLAM's geometric split of max_features) goes first
//                 to the best corner of each grid cell, then to the best of the rest
//   orientation   intensity centroid over a disc of radius 15 (Rublee et al. 2011)
//   descriptor    256 intensity comparisons of 5x5 box sums (the ORB paper's sub-windows;
//                 a box-sum image per level, SIMD kernel) at point pairs steered by the orientation in 30 steps
//                 of 12 degrees; the pairs: a fixed Gaussian pattern (BRIEF G II, sigma 31/5,
//                 within radius 13) drawn once from the project's RNG (grid_orb.cpp)
//
// Keypoints come out in level-0 pixel coordinates (pixel centres aligned across levels),
// `octave` the level, `size` 31 pixels at that level's scale, `angle` in degrees,
// `response` the FAST score.
#include <array>
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "rgbd_odometry/pipeline/pipeline_config.hpp"
#include "rgbd_odometry/pipeline/features.hpp"
#include "rgbd_odometry/pipeline/task_runner.hpp"
#include "rgbd_odometry/simd/kernels.hpp"

namespace rgbdo {

class GridOrbExtractor {
 public:
  // Sizes every buffer for width x height frames and the configuration's levels and budget.
  // With a runner, the levels' corners and descriptors are found in parallel tasks (the
  // result is the same).
  GridOrbExtractor(const FeatureConfig& config, int width, int height, TaskRunner* runner = nullptr);

  // Detects inside mask (CV_8UC1, 255 = allowed, gray's size) and describes; out is
  // overwritten, reusing its buffers.
  void detect(const cv::Mat& gray, const cv::Mat& mask, Features& out);
  bool sized_for(int width, int height) const { return width == width_ && height == height_; }

  static constexpr int kFastLowThreshold = 7;
  // Corners at the full threshold per keypoint wanted below which a level falls back to the
  // low threshold in its empty cells (fr1_xyz's textured levels have 15 to 40).
  static constexpr int kFallbackMargin = 4;
  static constexpr int kBorder = 16;  // orientation disc (15) and descriptor support (13 + 2), from each level's edge
  static constexpr int kAngleSteps = 30;
  static constexpr int kDescriptorBits = 256;

  struct PointPair {
    std::int8_t x1, y1, x2, y2;
  };
  // The descriptor's comparisons at angle 0 (for tests and documentation).
  static const std::array<PointPair, kDescriptorBits>& pattern();

 private:
  struct Candidate {
    int x, y;       // level pixels
    int score;      // FAST score at the threshold the cell used
    bool strong;    // a corner at fast_threshold (not only at the low fallback)
  };
  struct Level {
    cv::Mat image;                   // CV_8UC1
    // 5x5 box sums of the image, rows box_stride_ apart (one stride for every level, so one
    // table of steered offsets serves them all); 2 pixels from the edges and inwards.
    std::vector<std::uint16_t> box;
    double scale = 1;                // level-0 pixels per level pixel
    int budget = 0;                  // keypoints wanted from this level
    int cell_px = 32;                // grid cell edge in level pixels
    // Downscaling from the previous level: per output row its source row and weight (of the
    // next row, in 1/256); the columns as the horizontal kernel's groups of eight.
    std::vector<int> y0;
    std::vector<std::uint16_t> wy;
    std::vector<simd::ResampleGroup> x_groups;
    std::vector<int> mask_x, mask_y;  // the level-0 column (row) of each level column (row): mask look-ups
    // The level's own detection state, so that levels can be detected in parallel.
    std::vector<Candidate> candidates, chosen;
    std::vector<std::uint16_t> score;  // per pixel; 0 = no corner (clean between frames)
    std::vector<std::uint8_t> flags;   // one row of FAST flags
    std::vector<int> cell_state;       // per cell: kHasCorner at the full threshold, kSearchLow, or 0
    int first_keypoint = 0;            // where its keypoints start in the frame's list
  };

  // The constructor's steps after the levels' sizes and budgets: each level's resampling from
  // the one above it, the buffers detection fills (so that it never allocates), the pattern
  // steered to every orientation step.
  static void plan_resampling(Level& L, const Level& src, double step);
  void reserve_detection_buffers();
  void steer_pattern();
  void build_pyramid(const cv::Mat& gray);
  void build_box_sums(Level& level) const;
  void detect_level(Level& level, const cv::Mat& mask) const;
  static void mark_cells_to_search(const Level& level, const cv::Mat& mask, int yb, int ye, int cells_x,
                                   int* row_cells, int& first, int& last);
  void suppress_non_maxima(Level& level) const;
  void select_level(Level& level);
  void describe_level(const Level& level, int octave, Features& out) const;
  float orientation(const Level& level, int x, int y) const;
  void describe(const Level& level, int x, int y, float angle_deg, std::uint8_t* out) const;

  FeatureConfig config_;
  int width_, height_;
  std::vector<Level> levels_;
  // The active kernel set's, bound once.
  simd::Fast9RowFn fast9_row_;
  simd::Fast9ScoreFn fast9_score_;
  simd::BlendRowsFn blend_rows_;
  simd::ResampleRowFn resample_row_;
  simd::Box5RowFn box5_row_;
  simd::DiscMomentsFn disc_moments_;
  int box_stride_;
  TaskRunner* runner_;
  std::vector<std::uint8_t> row_buffer_;  // one level-0 row (+16 readable bytes): a blended pyramid row
  std::vector<int> cell_best_;            // selection (one level at a time)
  // Per orientation step and comparison, the offsets of its two boxes in a box image.
  std::array<std::array<std::array<std::int32_t, 2>, kDescriptorBits>, kAngleSteps> steered_offsets_;
};

}  // namespace rgbdo
