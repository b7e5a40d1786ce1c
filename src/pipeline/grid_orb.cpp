#include "rgbd_odometry/pipeline/grid_orb.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <utility>

#include "rgbd_odometry/core/cost_stage.hpp"
#include "rgbd_odometry/core/rng.hpp"
#include "rgbd_odometry/simd/kernels.hpp"

// Everything that decides a keypoint or a descriptor bit is integer arithmetic (or tables made
// once from IEEE basic operations), so that the x86-64 and the armhf builds choose the same
// keypoints and bits: libm's last bits differ between them (test/README.md, the armhf build).
namespace rgbdo {
namespace {

constexpr int kPatternRadius = 13;
constexpr int kMinCellPx = 12, kMaxCellPx = 64;
constexpr std::uint64_t kPatternSeed = 0x4752494430524231ULL;  // "GRID0RB1": the pattern is fixed by it

// A standard normal draw in integers (Irwin-Hall: 12 uniforms of 1/1024 steps, variance
// 1024^2 up to 0.0001 %), so that the pattern is the same on every architecture.
int gaussian_1024(Rng& rng) {
  int sum = 0;
  for (int i = 0; i < 12; ++i) sum += static_cast<int>(rng.below(1024));
  return sum - 12 * 1023 / 2;
}

std::array<GridOrbExtractor::PointPair, GridOrbExtractor::kDescriptorBits> make_pattern() {
  // BRIEF's G II sampling (Calonder et al. 2010): both points of a test i.i.d. Gaussian about
  // the centre with sigma = S / 5 for an S = 31 patch; kept within the disc that every
  // rotation maps onto itself.
  Rng rng(kPatternSeed);
  const auto draw = [&](std::int8_t& x, std::int8_t& y) {
    for (;;) {
      // sigma 31/5 = 6.2: x = round(g * 6.2 / 1024) with g ~ N(0, 1024^2), in integers
      const int gx = gaussian_1024(rng), gy = gaussian_1024(rng);
      const int dx = (gx * 62 + (gx >= 0 ? 5120 : -5120)) / 10240;
      const int dy = (gy * 62 + (gy >= 0 ? 5120 : -5120)) / 10240;
      if (dx * dx + dy * dy <= kPatternRadius * kPatternRadius) {
        x = static_cast<std::int8_t>(dx);
        y = static_cast<std::int8_t>(dy);
        return;
      }
    }
  };
  std::array<GridOrbExtractor::PointPair, GridOrbExtractor::kDescriptorBits> pattern{};
  for (auto& p : pattern) {
    do {
      draw(p.x1, p.y1);
      draw(p.x2, p.y2);
    } while (p.x1 == p.x2 && p.y1 == p.y2);
  }
  return pattern;
}

// Unit vectors of the orientation steps in 1/65536 (no value lies near a rounding tie).
struct Direction {
  std::int64_t c, s;
};
const std::array<Direction, GridOrbExtractor::kAngleSteps>& directions() {
  static const auto table = [] {
    std::array<Direction, GridOrbExtractor::kAngleSteps> d{};
    for (int k = 0; k < GridOrbExtractor::kAngleSteps; ++k) {
      const double a = 2.0 * M_PI * k / GridOrbExtractor::kAngleSteps;
      d[static_cast<size_t>(k)] = {std::llround(std::cos(a) * 65536.0), std::llround(std::sin(a) * 65536.0)};
    }
    return d;
  }();
  return table;
}

// Rounds a / 65536 to the nearest integer, halves away from zero (exact integer arithmetic).
inline int round_q16(std::int64_t a) { return static_cast<int>(a >= 0 ? (a + 32768) >> 16 : -((-a + 32768) >> 16)); }

// A grid cell's state in a level's low-threshold fallback (Level::cell_state).
constexpr int kHasCorner = 1, kSearchLow = 2;

// Candidate order: corners at the full threshold first, then by score, then top to bottom,
// left to right: a total order, so every build picks the same keypoints.
inline bool better(int a_strong, int a_score, int a_y, int a_x, int b_strong, int b_score, int b_y, int b_x) {
  if (a_strong != b_strong) return a_strong > b_strong;
  if (a_score != b_score) return a_score > b_score;
  if (a_y != b_y) return a_y < b_y;
  return a_x < b_x;
}

}  // namespace

const std::array<GridOrbExtractor::PointPair, GridOrbExtractor::kDescriptorBits>& GridOrbExtractor::pattern() {
  static const auto p = make_pattern();
  return p;
}

GridOrbExtractor::GridOrbExtractor(const FeatureConfig& config, int width, int height, TaskRunner* runner)
    : config_(config),
      width_(width),
      height_(height),
      fast9_row_(simd::active_kernels().fast9_row),
      fast9_score_(simd::active_kernels().fast9_score),
      blend_rows_(simd::active_kernels().blend_rows),
      resample_row_(simd::active_kernels().resample_row),
      box5_row_(simd::active_kernels().box5_row),
      disc_moments_(simd::active_kernels().disc_moments),
      box_stride_(width),
      runner_(runner) {
  const int n_levels = config.orb_levels;
  const double factor = 1.0 / config.orb_scale_factor;
  levels_.resize(static_cast<size_t>(n_levels));
  // ORB-SLAM's split of the budget: geometric in the inverse scale factor, level 0 most.
  double per_level = config.max_features * (1 - factor) / (1 - std::pow(factor, n_levels));
  int assigned = 0;
  double scale = 1;
  for (int l = 0; l < n_levels; ++l) {
    Level& L = levels_[static_cast<size_t>(l)];
    L.scale = scale;
    const int w = l == 0 ? width : static_cast<int>(std::lround(width / scale));
    const int h = l == 0 ? height : static_cast<int>(std::lround(height / scale));
    L.image.create(h, w, CV_8UC1);
    L.box.assign(static_cast<size_t>(box_stride_) * static_cast<size_t>(h), 0);
    // The level-0 pixel under each level pixel's centre, for the mask.
    for (int x = 0; x < w; ++x) L.mask_x.push_back(std::min(static_cast<int>((x + 0.5) * L.scale), width - 1));
    for (int y = 0; y < h; ++y) L.mask_y.push_back(std::min(static_cast<int>((y + 0.5) * L.scale), height - 1));
    L.budget = l == n_levels - 1 ? std::max(config.max_features - assigned, 0) : static_cast<int>(std::lround(per_level));
    assigned += L.budget;
    per_level *= factor;
    const int usable = std::max(w - 2 * kBorder, 1) * std::max(h - 2 * kBorder, 1);
    L.cell_px = std::clamp(static_cast<int>(std::sqrt(usable / std::max(L.budget, 1))), kMinCellPx, kMaxCellPx);
    if (l > 0) plan_resampling(L, levels_[static_cast<size_t>(l - 1)], config.orb_scale_factor);
    scale *= config.orb_scale_factor;
  }
  row_buffer_.assign(static_cast<size_t>(width) + 16, 0);  // + what a resampling kernel may read past a row
  reserve_detection_buffers();
  steer_pattern();
}

// Each output pixel centre's source in the previous level, pixel centres aligned: the rows'
// first source row and weight, the columns' in groups of eight for the kernels.
void GridOrbExtractor::plan_resampling(Level& L, const Level& src, double step) {
  const int w = L.image.cols, h = L.image.rows;
  // The source pixel left of the output centre and the right one's weight; a weight that
  // rounds to 256 is the next pixel's 0, so weights fit a byte (the kernels' form).
  const auto source = [&](int o, int n_src) {
    const double s = (o + 0.5) * step - 0.5;
    int i = static_cast<int>(std::floor(s));
    int w8 = static_cast<int>(std::lround((s - i) * 256));
    if (w8 == 256) ++i, w8 = 0;
    if (i < 0) i = 0, w8 = 0;
    if (i >= n_src - 1) i = n_src - 1, w8 = 0;
    return std::pair{i, w8};
  };
  L.y0.resize(static_cast<size_t>(h));
  L.wy.resize(static_cast<size_t>(h));
  for (int o = 0; o < h; ++o) {
    const auto [i, w8] = source(o, src.image.rows);
    L.y0[static_cast<size_t>(o)] = i;
    L.wy[static_cast<size_t>(o)] = static_cast<std::uint16_t>(w8);
  }
  L.x_groups.assign(static_cast<size_t>((w + 7) / 8), simd::ResampleGroup{});
  for (int o = 0; o < w; ++o) {
    const auto [i, w8] = source(o, src.image.cols);
    simd::ResampleGroup& g = L.x_groups[static_cast<size_t>(o / 8)];
    if (o % 8 == 0) g.base = i;
    // Eight outputs span at most 7 * 2 + 1 source pixels at scale factors up to 2 (the
    // configuration's limit): index + 1 stays within the 16 bytes a kernel loads.
    if (i - g.base + 1 > 15) throw std::logic_error("GRID_ORB: a pyramid step wider than 2");
    g.index[o % 8] = static_cast<std::uint8_t>(i - g.base);
    g.weight[o % 8] = static_cast<std::uint8_t>(w8);
  }
}

void GridOrbExtractor::reserve_detection_buffers() {
  // Bounds fixed here, so detection never allocates: corners before suppression at most one
  // pixel in four of a level (a real image has a few per cent; only noise reaches it, and the
  // scan then stops), cells as many as the smallest cell makes.
  const size_t max_cells = static_cast<size_t>(width_ / kMinCellPx + 1) * static_cast<size_t>(height_ / kMinCellPx + 1);
  cell_best_.reserve(max_cells);
  for (Level& L : levels_) {
    const auto pixels = static_cast<size_t>(L.image.cols) * static_cast<size_t>(L.image.rows);
    L.candidates.reserve(pixels / 4);
    L.chosen.reserve(max_cells + static_cast<size_t>(config_.max_features));
    L.score.assign(pixels, 0);
    L.flags.assign(static_cast<size_t>(L.image.cols), 0);
    L.cell_state.reserve(max_cells);
  }
}

void GridOrbExtractor::steer_pattern() {
  // The pattern steered to every orientation step, rounded in integers, as offsets in a box image.
  const auto& base = pattern();
  for (int k = 0; k < kAngleSteps; ++k) {
    const Direction d = directions()[static_cast<size_t>(k)];
    for (int i = 0; i < kDescriptorBits; ++i) {
      const PointPair& p = base[static_cast<size_t>(i)];
      const auto offset = [&](int x, int y) {
        return round_q16(d.s * x + d.c * y) * box_stride_ + round_q16(d.c * x - d.s * y);
      };
      steered_offsets_[static_cast<size_t>(k)][static_cast<size_t>(i)] = {offset(p.x1, p.y1), offset(p.x2, p.y2)};
    }
  }
}

void GridOrbExtractor::build_pyramid(const cv::Mat& gray) {
  gray.copyTo(levels_[0].image);  // same size every frame: no allocation
  for (size_t l = 1; l < levels_.size(); ++l) {
    const Level& src = levels_[l - 1];
    Level& dst = levels_[l];
    std::uint8_t* blended = row_buffer_.data();
    for (int y = 0; y < dst.image.rows; ++y) {
      // Vertically along whole source rows, then horizontally; each pass rounds to 8 bits.
      const int y0 = dst.y0[static_cast<size_t>(y)];
      const std::uint8_t* r0 = src.image.ptr<std::uint8_t>(y0);
      const std::uint8_t* r1 = src.image.ptr<std::uint8_t>(std::min(y0 + 1, src.image.rows - 1));
      blend_rows_(r0, r1, src.image.cols, dst.wy[static_cast<size_t>(y)], blended);
      resample_row_(blended, dst.x_groups.data(), dst.image.cols, dst.image.ptr<std::uint8_t>(y));
    }
  }
}

void GridOrbExtractor::build_box_sums(Level& L) const {
  const int w = L.image.cols, h = L.image.rows;
  if (w < 5) return;
  const auto stride = static_cast<std::ptrdiff_t>(L.image.step);
  for (int y = 2; y < h - 2; ++y)
    box5_row_(L.image.ptr<std::uint8_t>(y) + 2, stride, w - 4, L.box.data() + static_cast<size_t>(y) * static_cast<size_t>(box_stride_) + 2);
}

void GridOrbExtractor::detect_level(Level& L, const cv::Mat& mask) const {
  const int w = L.image.cols, h = L.image.rows;
  const auto stride = static_cast<int>(L.image.step);
  std::array<std::ptrdiff_t, 16> circle_offset{};  // FAST circle (radius 3) at this level's stride
  for (int k = 0; k < 16; ++k) circle_offset[static_cast<size_t>(k)] = simd::kFastCircle[k][1] * stride + simd::kFastCircle[k][0];
  const int cells_x = (w - 2 * kBorder + L.cell_px - 1) / L.cell_px;
  const int cells_y = (h - 2 * kBorder + L.cell_px - 1) / L.cell_px;
  std::vector<Candidate>& candidates = L.candidates;
  candidates.clear();

  // The segment test at threshold t over [x_begin, x_end) x [y_begin, y_end) (the active SIMD
  // kernel flags the corners), then each corner's mask and score; appends the corners. With
  // `cells` (one row of the cell grid, its first cell at kBorder), only corners in cells marked
  // kSearchLow there.
  const auto segment_test = [&](int t, int x_begin, int x_end, int y_begin, int y_end, bool strong,
                                const int* cells) {
    std::uint8_t* flags = L.flags.data();
    for (int y = y_begin; y < y_end; ++y) {
      const std::uint8_t* row = L.image.ptr<std::uint8_t>(y);
      const std::uint8_t* mask_row = mask.ptr<std::uint8_t>(L.mask_y[static_cast<size_t>(y)]);
      fast9_row_(row + x_begin, stride, x_end - x_begin, t, flags);
      const int n = x_end - x_begin;
      for (int i = 0; i < n; ++i) {
        // Corners are sparse: skip eight flags at a time while they are all zero.
        if ((i & 7) == 0 && i + 8 <= n) {
          std::uint64_t eight;
          std::memcpy(&eight, flags + i, sizeof eight);
          if (eight == 0) {
            i += 7;
            continue;
          }
        }
        if (flags[i] == 0) continue;
        const int x = x_begin + i;
        if (cells != nullptr && cells[(x - kBorder) / L.cell_px] != kSearchLow) continue;
        // Only inside the mask (periphery, no depth), looked up at the level-0 pixel.
        if (mask_row[L.mask_x[static_cast<size_t>(x)]] == 0) continue;
        // Score: the summed excess of the arc's side over the threshold (FAST-ER's SAD score),
        // at least 1 for a corner.
        const int score = fast9_score_(row + x, circle_offset.data(), t, flags[i]) + 1;
        // Bounded (sized at construction: no allocation); only noise fills it.
        if (candidates.size() == candidates.capacity()) return;
        candidates.push_back({x, y, score, strong});
      }
    }
  };
  const int x_begin = kBorder, x_end = w - kBorder, y_begin = kBorder, y_end = h - kBorder;
  if (x_end <= x_begin || y_end <= y_begin) return;
  segment_test(config_.fast_threshold, x_begin, x_end, y_begin, y_end, true, nullptr);
  // A level with corners to spare (textured, sharp) keeps to the full threshold: measured on
  // fr1_xyz, its weak corners cost ~23 M ARM instructions per frame and made the odometry no
  // better. When blur or a bare scene leaves fewer than kFallbackMargin corners per keypoint
  // wanted, cells without a corner look again at the low threshold (ORB-SLAM's fallback).
  const auto nms = [&] { suppress_non_maxima(L); };
  if (candidates.size() >= static_cast<size_t>(kFallbackMargin * std::max(L.budget, 1))) return nms();
  std::vector<int>& state = L.cell_state;
  state.assign(static_cast<size_t>(std::max(cells_x, 0) * std::max(cells_y, 0)), 0);
  for (const Candidate& c : candidates)
    state[static_cast<size_t>(((c.y - kBorder) / L.cell_px) * cells_x + (c.x - kBorder) / L.cell_px)] = kHasCorner;
  // One segment test per row of cells, over the span from its first cell to search to its last
  // (not one per cell: a bare scene searches nearly every cell, and the kernel's per-call and
  // per-row-tail costs had made its corners 72.2 M ARM instructions a frame, a textured
  // frame's 18-20 M). At most a second pass over the level, whatever the scene.
  for (int cy = 0; cy < cells_y; ++cy) {
    int* row_cells = state.data() + static_cast<size_t>(cy) * static_cast<size_t>(cells_x);
    const int yb = y_begin + cy * L.cell_px, ye = std::min(yb + L.cell_px, y_end);
    int first = -1, last = -1;
    mark_cells_to_search(L, mask, yb, ye, cells_x, row_cells, first, last);
    if (first < 0) continue;
    segment_test(kFastLowThreshold, x_begin + first * L.cell_px, std::min(x_begin + (last + 1) * L.cell_px, x_end), yb,
                 ye, false, row_cells);
  }

  nms();
}

// Marks kSearchLow the cells of one row of the grid (rows yb..ye of the level) that found no
// corner at the full threshold and see any of the mask (sampled every 4 level pixels: a cell
// wholly outside it, no depth or the periphery, is not searched again); first and last: the
// span of the marked cells (-1: none).
void GridOrbExtractor::mark_cells_to_search(const Level& L, const cv::Mat& mask, int yb, int ye, int cells_x,
                                            int* row_cells, int& first, int& last) {
  const int x_end = L.image.cols - kBorder;
  for (int cx = 0; cx < cells_x; ++cx) {
    if (row_cells[cx] == kHasCorner) continue;
    const int xb = kBorder + cx * L.cell_px, xe = std::min(xb + L.cell_px, x_end);
    bool in_mask = false;
    for (int y = yb; y < ye && !in_mask; y += 4) {
      const std::uint8_t* mask_row = mask.ptr<std::uint8_t>(L.mask_y[static_cast<size_t>(y)]);
      for (int x = xb; x < xe && !in_mask; x += 4) in_mask = mask_row[L.mask_x[static_cast<size_t>(x)]] != 0;
    }
    if (!in_mask) continue;
    row_cells[cx] = kSearchLow;
    if (first < 0) first = cx;
    last = cx;
  }
}

void GridOrbExtractor::suppress_non_maxima(Level& L) const {
  const int w = L.image.cols;
  std::vector<Candidate>& candidates = L.candidates;
  std::vector<std::uint16_t>& score = L.score;
  // 3x3 non-maximum suppression on the score image (strict against earlier pixels, so that of
  // two equal neighbours exactly one survives).
  for (const Candidate& c : candidates) score[static_cast<size_t>(c.y * w + c.x)] = static_cast<std::uint16_t>(c.score);
  for (Candidate& c : candidates) {
    const std::uint16_t* s = score.data() + c.y * w + c.x;
    const int v = *s;
    const bool is_max = v >= s[-w - 1] && v >= s[-w] && v >= s[-w + 1] && v >= s[-1] && v > s[1] && v > s[w - 1] &&
                        v > s[w] && v > s[w + 1];
    if (!is_max) c.score = 0;  // suppressed
  }
  // The score image clean again for the next level, before any candidate is dropped.
  for (const Candidate& c : candidates) score[static_cast<size_t>(c.y * w + c.x)] = 0;
  candidates.erase(std::remove_if(candidates.begin(), candidates.end(), [](const Candidate& c) { return c.score == 0; }),
                   candidates.end());
}

void GridOrbExtractor::select_level(Level& L) {
  std::vector<Candidate>& candidates = L.candidates;
  std::vector<Candidate>& chosen = L.chosen;
  const int w = L.image.cols, h = L.image.rows;
  const int cells_x = (w - 2 * kBorder + L.cell_px - 1) / L.cell_px;
  const int cells_y = (h - 2 * kBorder + L.cell_px - 1) / L.cell_px;
  cell_best_.assign(static_cast<size_t>(std::max(cells_x, 0) * std::max(cells_y, 0)), -1);
  const auto cand_better = [](const Candidate& a, const Candidate& b) {
    return better(a.strong, a.score, a.y, a.x, b.strong, b.score, b.y, b.x);
  };
  // The best corner of each cell first: keypoints spread over the image, not clumped on texture.
  for (size_t i = 0; i < candidates.size(); ++i) {
    const Candidate& c = candidates[i];
    int& best = cell_best_[static_cast<size_t>(((c.y - kBorder) / L.cell_px) * cells_x + (c.x - kBorder) / L.cell_px)];
    if (best < 0 || cand_better(c, candidates[static_cast<size_t>(best)])) best = static_cast<int>(i);
  }
  chosen.clear();
  for (const int best : cell_best_)
    if (best >= 0) {
      chosen.push_back(candidates[static_cast<size_t>(best)]);
      candidates[static_cast<size_t>(best)].score = -1;  // taken
    }
  const auto budget = static_cast<size_t>(std::max(L.budget, 0));
  if (chosen.size() > budget) {
    std::partial_sort(chosen.begin(), chosen.begin() + static_cast<std::ptrdiff_t>(budget), chosen.end(), cand_better);
    chosen.resize(budget);
  } else if (chosen.size() < budget) {
    // Then the best of the rest.
    const auto taken_last = std::remove_if(candidates.begin(), candidates.end(), [](const Candidate& c) { return c.score < 0; });
    candidates.erase(taken_last, candidates.end());
    const size_t more = std::min(budget - chosen.size(), candidates.size());
    std::partial_sort(candidates.begin(), candidates.begin() + static_cast<std::ptrdiff_t>(more), candidates.end(),
                      cand_better);
    chosen.insert(chosen.end(), candidates.begin(), candidates.begin() + static_cast<std::ptrdiff_t>(more));
  }
  std::sort(chosen.begin(), chosen.end(), [](const Candidate& a, const Candidate& b) {
    return a.y != b.y ? a.y < b.y : a.x < b.x;
  });
}

void GridOrbExtractor::describe_level(const Level& L, int octave, Features& out) const {
  const float size = static_cast<float>(31.0 * L.scale);
  size_t row = static_cast<size_t>(L.first_keypoint);
  for (const Candidate& c : L.chosen) {
    const float angle = orientation(L, c.x, c.y);
    cv::KeyPoint kp;
    kp.pt = {static_cast<float>((c.x + 0.5) * L.scale - 0.5), static_cast<float>((c.y + 0.5) * L.scale - 0.5)};
    kp.size = size;
    kp.angle = angle;
    kp.response = static_cast<float>(c.score);
    kp.octave = octave;
    kp.class_id = -1;
    out.keypoints[row] = kp;
    describe(L, c.x, c.y, angle, out.descriptor_storage.ptr<std::uint8_t>(static_cast<int>(row)));
    ++row;
  }
}

float GridOrbExtractor::orientation(const Level& L, int x, int y) const {
  // Intensity centroid: the direction from the keypoint to the disc's centre of brightness,
  // snapped to the nearest of the 30 steps by integer dot products (no atan2: its last bits
  // differ between builds).
  std::int32_t m10 = 0, m01 = 0;
  disc_moments_(L.image.ptr<std::uint8_t>(y) + x, static_cast<std::ptrdiff_t>(L.image.step), &m10, &m01);
  int best = 0;
  std::int64_t best_dot = std::numeric_limits<std::int64_t>::min();
  for (int k = 0; k < kAngleSteps; ++k) {
    const Direction d = directions()[static_cast<size_t>(k)];
    const std::int64_t dot = m10 * d.c + m01 * d.s;
    if (dot > best_dot) best_dot = dot, best = k;
  }
  return static_cast<float>(best * (360 / kAngleSteps));
}

void GridOrbExtractor::describe(const Level& L, int x, int y, float angle_deg, std::uint8_t* out) const {
  const auto step = static_cast<size_t>(std::lround(angle_deg / (360.0f / kAngleSteps))) % kAngleSteps;
  const auto& offsets = steered_offsets_[step];
  const std::uint16_t* centre = L.box.data() + static_cast<size_t>(y) * static_cast<size_t>(box_stride_) + x;
  for (int byte = 0; byte < kDescriptorBits / 8; ++byte) {
    unsigned bits = 0;
    for (int b = 0; b < 8; ++b) {
      const auto& o = offsets[static_cast<size_t>(byte * 8 + b)];
      bits |= static_cast<unsigned>(centre[o[0]] < centre[o[1]]) << b;
    }
    out[byte] = static_cast<std::uint8_t>(bits);
  }
}

void GridOrbExtractor::detect(const cv::Mat& gray, const cv::Mat& mask, Features& out) {
  CV_Assert(gray.type() == CV_8UC1 && gray.cols == width_ && gray.rows == height_);
  CV_Assert(mask.type() == CV_8UC1 && mask.size() == gray.size());
  out.keypoints.clear();
  if (out.descriptor_storage.rows < config_.max_features || out.descriptor_storage.cols != kDescriptorBits / 8)
    out.descriptor_storage.create(config_.max_features, kDescriptorBits / 8, CV_8UC1);
  mark_cost_stage(CostStage::Pyramid);
  build_pyramid(gray);
  // Every level's box sums and corners, each level a task of its own (they share nothing).
  const int n_levels = static_cast<int>(levels_.size());
  auto find_corners = [&](int l) {
    Level& L = levels_[static_cast<size_t>(l)];
    mark_cost_stage(CostStage::Pyramid);
    build_box_sums(L);
    mark_cost_stage(CostStage::Corners);
    detect_level(L, mask);
  };
  run_tasks(runner_, n_levels, find_corners);
  // The keypoints of each level in turn: budget a level could not use goes to the next.
  mark_cost_stage(CostStage::Corners);
  int carried = 0, total = 0;
  for (Level& L : levels_) {
    const int own = L.budget;
    L.budget += carried;
    select_level(L);
    carried = L.budget - static_cast<int>(L.chosen.size());
    L.budget = own;
    L.first_keypoint = total;
    total += static_cast<int>(L.chosen.size());
  }
  out.keypoints.resize(static_cast<size_t>(total));  // within the capacity of earlier frames
  auto describe_keypoints = [&](int l) {
    mark_cost_stage(CostStage::Detect);
    describe_level(levels_[static_cast<size_t>(l)], l, out);
  };
  run_tasks(runner_, n_levels, describe_keypoints);
  mark_cost_stage(CostStage::Detect);
  out.descriptors = out.descriptor_storage.rowRange(0, static_cast<int>(out.keypoints.size()));
}

}  // namespace rgbdo
