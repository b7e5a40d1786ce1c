#include "rgbd_odometry/pipeline/match.hpp"

#include <algorithm>
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

// keep_nearest_two's record for candidates met in any order: among equal distances the lowest
// index wins, as it does when they come in index order.
inline void keep_nearest_two_any_order(simd::NearestTwo& n, std::uint32_t d, int index) {
  if (d < n.best || (d == n.best && index < n.best_index)) {
    n.second = n.best;
    n.best = d;
    n.best_index = index;
  } else if (d < n.second) {
    n.second = d;
  }
}

// At most this many grid cells per axis: a tiny radius must not make the grid huge.
constexpr int kMaxGridCells = 64;

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

void SymmetricMatcher::reserve(int max_features) {
  const auto n = static_cast<size_t>(max_features);
  for (auto* v : {&prev_nn_, &curr_nn_}) v->reserve(n);
  for (auto* v : {&cell_of_, &by_cell_, &candidates_}) v->reserve(n);
  by_cell_position_.reserve(n);
  distances_.reserve(n);
  cell_start_.reserve(kMaxGridCells * kMaxGridCells + 1);
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
  keep_mutual(prev.rows, binary, out);
}

void SymmetricMatcher::match_within(const cv::Mat& prev, const cv::Mat& curr, std::span<const Eigen::Vector2d> predicted,
                                    std::span<const Eigen::Vector2d> curr_positions, double radius,
                                    std::vector<Match>& out) {
  out.clear();
  if (prev.empty() || curr.empty()) return;
  CV_Assert(prev.type() == CV_8UC1 && curr.type() == CV_8UC1 && prev.cols == curr.cols);
  CV_Assert(predicted.size() == static_cast<size_t>(prev.rows) && curr_positions.size() == static_cast<size_t>(curr.rows));
  CV_Assert(radius > 0);
  prev_nn_.assign(static_cast<size_t>(prev.rows), simd::NearestTwo{});
  curr_nn_.assign(static_cast<size_t>(curr.rows), simd::NearestTwo{});
  const std::optional<Grid> grid = Grid::over(curr_positions, radius, kMaxGridCells);
  if (!grid) return;  // no finite position
  sort_by_cell(*grid, curr_positions);

  for (int i = 0; i < prev.rows; ++i) {
    const int n = window_candidates(*grid, predicted[static_cast<size_t>(i)], radius);
    if (n == 0) continue;
    hamming_rows_(prev.ptr<std::uint8_t>(i), curr.data, curr.step, candidates_.data(), n, prev.cols, distances_.data());
    simd::NearestTwo& forward = prev_nn_[static_cast<size_t>(i)];
    for (int k = 0; k < n; ++k) {
      const int j = candidates_[static_cast<size_t>(k)];
      const std::uint32_t d = distances_[static_cast<size_t>(k)];
      keep_nearest_two_any_order(forward, d, j);
      keep_nearest_two_any_order(curr_nn_[static_cast<size_t>(j)], d, i);
    }
  }
  keep_mutual(prev.rows, true, out);
}

// The grid: cells at least `radius` wide, so a window spans at most 3 x 3 of them.
std::optional<SymmetricMatcher::Grid> SymmetricMatcher::Grid::over(std::span<const Eigen::Vector2d> positions,
                                                                   double radius, int max_cells) {
  Grid g;
  for (const Eigen::Vector2d& p : positions) {
    g.min_x = std::min(g.min_x, p.x()), g.max_x = std::max(g.max_x, p.x());
    g.min_y = std::min(g.min_y, p.y()), g.max_y = std::max(g.max_y, p.y());
  }
  if (!(g.max_x >= g.min_x && g.max_y >= g.min_y)) return std::nullopt;
  g.cell_w = std::max(radius, (g.max_x - g.min_x) / (max_cells - 1));
  g.cell_h = std::max(radius, (g.max_y - g.min_y) / (max_cells - 1));
  g.nx = std::min(static_cast<int>((g.max_x - g.min_x) / g.cell_w) + 1, max_cells);
  g.ny = std::min(static_cast<int>((g.max_y - g.min_y) / g.cell_h) + 1, max_cells);
  return g;
}

// Clamped in floating point first: a far-off or NaN position must not overflow the int. Where
// it is not negative, the conversion's truncation is the floor (std::floor is a libm call on
// ARMv7, 0.4 M instructions a frame here).
int SymmetricMatcher::Grid::cell_x(double x) const {
  const double c = (x - min_x) / cell_w;
  return c >= 0 ? static_cast<int>(std::min(c, static_cast<double>(nx))) : -1;
}

int SymmetricMatcher::Grid::cell_y(double y) const {
  const double c = (y - min_y) / cell_h;
  return c >= 0 ? static_cast<int>(std::min(c, static_cast<double>(ny))) : -1;
}

// Counting sort of the current keypoints by cell (index order within a cell).
void SymmetricMatcher::sort_by_cell(const Grid& g, std::span<const Eigen::Vector2d> curr_positions) {
  const auto rows = static_cast<int>(curr_positions.size());
  cell_start_.assign(static_cast<size_t>(g.nx * g.ny + 1), 0);
  cell_of_.resize(static_cast<size_t>(rows));
  for (int j = 0; j < rows; ++j) {
    const Eigen::Vector2d& p = curr_positions[static_cast<size_t>(j)];
    const int cx = g.cell_x(p.x()), cy = g.cell_y(p.y());
    const bool inside = cx >= 0 && cx < g.nx && cy >= 0 && cy < g.ny;  // false only for NaN
    cell_of_[static_cast<size_t>(j)] = inside ? cy * g.nx + cx : -1;
    if (inside) ++cell_start_[static_cast<size_t>(cy * g.nx + cx + 1)];
  }
  for (size_t c = 1; c < cell_start_.size(); ++c) cell_start_[c] += cell_start_[c - 1];
  by_cell_.resize(static_cast<size_t>(cell_start_.back()));
  by_cell_position_.resize(by_cell_.size());
  candidates_.resize(by_cell_.size());  // every search fills at most all of them
  distances_.resize(by_cell_.size());
  for (int j = 0; j < rows; ++j) {
    const int c = cell_of_[static_cast<size_t>(j)];
    if (c < 0) continue;
    // cell_start_[c] counts up as the cell fills; shifted back below.
    const auto slot = static_cast<size_t>(cell_start_[static_cast<size_t>(c)]++);
    by_cell_[slot] = j;
    by_cell_position_[slot] = curr_positions[static_cast<size_t>(j)];
  }
  for (size_t c = cell_start_.size() - 1; c > 0; --c) cell_start_[c] = cell_start_[c - 1];
  cell_start_[0] = 0;
}

// The current keypoints within `radius` of p (in both coordinates) into candidates_; how many.
int SymmetricMatcher::window_candidates(const Grid& g, const Eigen::Vector2d& p, double radius) {
  if (!std::isfinite(p.x()) || !std::isfinite(p.y())) return 0;
  const double lo_x = p.x() - radius, hi_x = p.x() + radius, lo_y = p.y() - radius, hi_y = p.y() + radius;
  if (hi_x < g.min_x || lo_x > g.max_x || hi_y < g.min_y || lo_y > g.max_y) return 0;  // window off the frame
  const int cx0 = std::max(g.cell_x(lo_x), 0), cx1 = std::min(g.cell_x(hi_x), g.nx - 1);
  const int cy0 = std::max(g.cell_y(lo_y), 0), cy1 = std::min(g.cell_y(hi_y), g.ny - 1);
  int n = 0;
  for (int cy = cy0; cy <= cy1; ++cy) {
    // The cells cx0..cx1 of one grid row are contiguous in by_cell_.
    const int begin = cell_start_[static_cast<size_t>(cy * g.nx + cx0)];
    const int end = cell_start_[static_cast<size_t>(cy * g.nx + cx1 + 1)];
    for (int k = begin; k < end; ++k) {
      const Eigen::Vector2d& q = by_cell_position_[static_cast<size_t>(k)];
      if (q.x() >= lo_x && q.x() <= hi_x && q.y() >= lo_y && q.y() <= hi_y)
        candidates_[static_cast<size_t>(n++)] = by_cell_[static_cast<size_t>(k)];
    }
  }
  return n;
}

void SymmetricMatcher::keep_mutual(int n_prev, bool binary, std::vector<Match>& out) const {
  const auto passes = [&](const simd::NearestTwo& n) {
    if (binary) return passes_ratio_test(n, ratio_);
    if (n.best_index < 0) return false;
    if (n.second == UINT32_MAX) return true;
    return as_distance(n.best, false) < ratio_ * as_distance(n.second, false);
  };
  for (int i = 0; i < n_prev; ++i) {
    const auto& forward = prev_nn_[static_cast<size_t>(i)];
    if (!passes(forward)) continue;
    const auto& backward = curr_nn_[static_cast<size_t>(forward.best_index)];
    if (backward.best_index != i || !passes(backward)) continue;
    out.push_back({i, forward.best_index, as_distance(forward.best, binary)});
  }
}

}  // namespace rgbdo
