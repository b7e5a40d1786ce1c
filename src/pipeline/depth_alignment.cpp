#include "rgbd_odometry/pipeline/depth_alignment.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <span>
#include <opencv2/calib3d.hpp>

#include "rgbd_odometry/pipeline/backproject.hpp"
#include "rgbd_odometry/simd/kernels.hpp"

namespace rgbdo {
namespace {

// chi^2(k) at 99.9 %, k = 1..6: two estimates of one motion further apart than this disagree.
constexpr std::array<double, 6> kAgreementGate{10.83, 13.82, 16.27, 18.47, 20.52, 22.46};
// A direction with less than this share of the best-constrained one's information carries none.
constexpr double kMinRelativeInformation = 1e-6;
// Fewer image cells with associations than this and the cells' spread says too little of
// the residuals' correlation: the alignment is not used.
constexpr int kMinCells = 8;
// DepthLagEstimate: the prior (L = 0) weighs as much as this many squared rad/s of rate
// change (a few pairs of a hand-held camera turning), and old pairs fade over this many.
constexpr double kLagPriorWeight = 0.05;
constexpr double kLagMemoryPairs = 300;
// The median of a chi^2(1) variable: a median of squared normal residuals over this is their variance.
constexpr double kChi2Median1 = 0.4549;
// Normals from the grid neighbours this many steps away: a longer baseline, less noise.
constexpr int kNormalReach = 1;
// The Gauss-Newton steps stop below these (m, rad).
constexpr double kStepTranslationM = 1e-5, kStepRotationRad = 1e-5;
// The shared rounding's depth units hashed into this many buckets: two units 0.8 m apart
// (at 5000 units/m) sharing one are counted as one (measured: no different from 65536).
constexpr int kRoundingBuckets = 4096;
// add_shared_rounding's glance: every this many-th association; below this share of the
// covariance (whitened trace) the shared rounding is not read in full.
constexpr int kRoundingGlance = 8;
constexpr double kRoundingNegligible = 0.2;

}  // namespace

void DepthCloud::clear() {
  cols = rows = 0;
  point.clear();
  normal.clear();
  raw_depth.clear();
  averaged.clear();
}

DepthCloudBuilder::DepthCloudBuilder(const CameraConfig& camera, const DepthConfig& depth,
                                     const RefinementConfig& refinement)
    : stride_(refinement.stride_px),
      cols_(camera.width / refinement.stride_px),
      rows_(camera.height / refinement.stride_px),
      width_(camera.width),
      height_(camera.height),
      depth_(depth) {
  // The grid is laid on the undistorted (pinhole) image, so that the alignment projects without
  // the lens model: sample (i, j) is the ray through the pinhole pixel (i s + s/2, j s + s/2),
  // read at the sensor pixel nearest to where the lens puts it, and its ray is that sensor
  // pixel's own (undistorted back), so that the point is exact and only its grid place rounded.
  // The depth pixel is the colour's moved by the depth image's registration (DepthConfig).
  const int half = stride_ / 2;
  std::vector<cv::Point3f> pinhole;
  for (int j = 0; j < rows_; ++j)
    for (int i = 0; i < cols_; ++i)
      pinhole.emplace_back(static_cast<float>((i * stride_ + half - camera.cx) / camera.fx),
                           static_cast<float>((j * stride_ + half - camera.cy) / camera.fy), 1.0f);
  const cv::Mat K = (cv::Mat_<double>(3, 3) << camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
  const cv::Mat distortion(1, 5, CV_64F, const_cast<double*>(camera.distortion.data()));
  std::vector<cv::Point2f> sensor, rays;
  cv::projectPoints(pinhole, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, distortion, sensor);
  std::vector<cv::Point2f> nearest;
  const double dx = depth.registration_x_px, dy = depth.registration_y_px;
  for (const cv::Point2f& p : sensor) {
    const auto u = static_cast<int>(std::lround(p.x - dx)), v = static_cast<int>(std::lround(p.y - dy));
    const bool inside = u >= 0 && v >= 0 && u < camera.width && v < camera.height;
    pixel_.push_back(inside ? v * camera.width + u : -1);
    nearest.emplace_back(static_cast<float>(inside ? u + dx : 0), static_cast<float>(inside ? v + dy : 0));
  }
  // Iterated to convergence, once: OpenCV's default 5 steps leave up to 0.13 px at the corners
  // of TUM fr1's lens, where the grid still samples (0.7 px behind a shorter focal length).
  undistort_pixels_exactly(camera, nearest, rays);
  for (const cv::Point2f& r : rays) ray_.emplace_back(r.x, r.y);
  if (refinement.average_depth)
    for (size_t k = 0; k < pixel_.size(); ++k) {
      const int u = pixel_[k] % camera.width, v = pixel_[k] / camera.width;
      if (pixel_[k] < 0 || u < 2 || v < 2 || u >= camera.width - 2 || v >= camera.height - 2) continue;
      averaged_sample_.push_back(static_cast<int>(k));
      averaged_pixel_.push_back(pixel_[k]);
    }
}

void DepthCloudBuilder::build(const cv::Mat& depth_m, DepthCloud& out) const {
  out.cols = cols_;
  out.rows = rows_;
  const auto n = static_cast<size_t>(cols_) * static_cast<size_t>(rows_);
  out.point.resize(n);
  out.normal.resize(n);
  const int half = stride_ / 2;
  const auto lo = static_cast<float>(depth_.min_m), hi = static_cast<float>(depth_.max_m);
  CV_Assert(depth_m.isContinuous() && depth_m.cols == width_ && depth_m.rows == height_);
  const auto* depth = depth_m.ptr<float>();
  out.raw_depth.resize(n);
  for (size_t k = 0; k < n; ++k) {
    const float z = pixel_[k] >= 0 ? depth[pixel_[k]] : 0.0f;
    const bool valid = z >= lo && z <= hi;
    out.raw_depth[k] = valid ? z : 0.0f;
    out.point[k] = valid ? Eigen::Vector3f(ray_[k].x() * z, ray_[k].y() * z, z) : Eigen::Vector3f::Zero();
  }
  // With refinement.average_depth, each sample the mean of the 5x5 pixels around it where they
  // are one surface (no hole, no step beyond the keypoints' edge rule over two pixels): the
  // aligner reads normals from neighbouring samples, and one pixel's noise of a Kinect's law
  // (0.9 % at 2.5 m) tilts them by degrees, enough to hold the alignment millimetres off along
  // the slide a far scene leaves between sideways translation and rotation
  // (src/pipeline/MEASUREMENTS.md#averaged-samples).
  out.averaged.resize(averaged_pixel_.size());
  if (!averaged_pixel_.empty())
    simd::active_kernels().surface_mean5(depth, width_, averaged_pixel_.data(), static_cast<int>(averaged_pixel_.size()),
                                         static_cast<float>(2 * depth_.edge_max_relative_step), out.averaged.data());
  for (size_t a = 0; a < averaged_pixel_.size(); ++a) {
    const auto k = static_cast<size_t>(averaged_sample_[a]);
    const float z = out.averaged[a];
    if (out.raw_depth[k] > 0 && z > 0) out.point[k] = Eigen::Vector3f(ray_[k].x() * z, ray_[k].y() * z, z);
  }
  // Normals from the four grid neighbours; none where a neighbour is missing or the depth
  // steps by more than an occlusion edge would (the keypoints' rule, over one grid step).
  const float max_step = static_cast<float>(depth_.edge_max_relative_step * std::max(1, half) * kNormalReach);
  for (int j = 0; j < rows_; ++j)
    for (int i = 0; i < cols_; ++i) {
      const size_t k = static_cast<size_t>(j) * static_cast<size_t>(cols_) + static_cast<size_t>(i);
      out.normal[k] = Eigen::Vector3f::Zero();
      if (i < kNormalReach || j < kNormalReach || i >= cols_ - kNormalReach || j >= rows_ - kNormalReach) continue;
      const Eigen::Vector3f& c = out.point[k];
      const size_t dx = kNormalReach, dy = static_cast<size_t>(kNormalReach * cols_);
      const Eigen::Vector3f& l = out.point[k - dx];
      const Eigen::Vector3f& r = out.point[k + dx];
      const Eigen::Vector3f& u = out.point[k - dy];
      const Eigen::Vector3f& d = out.point[k + dy];
      if (c.z() == 0 || l.z() == 0 || r.z() == 0 || u.z() == 0 || d.z() == 0) continue;
      const float step = max_step * c.z();
      if (std::abs(l.z() - c.z()) > step || std::abs(r.z() - c.z()) > step || std::abs(u.z() - c.z()) > step ||
          std::abs(d.z() - c.z()) > step)
        continue;
      Eigen::Vector3f nrm = (r - l).cross(d - u);
      const float len = nrm.norm();
      if (!(len > 0)) continue;
      nrm /= len;
      if (nrm.dot(c) > 0) nrm = -nrm;  // towards the camera
      out.normal[k] = nrm;
    }
}

std::array<float, 4> grid_intrinsics(const CameraConfig& camera, int stride_px) {
  const int half = stride_px / 2;  // sample i is the pinhole pixel i s + s/2 (DepthCloudBuilder)
  return {static_cast<float>(camera.fx / stride_px), static_cast<float>(camera.fy / stride_px),
          static_cast<float>((camera.cx - half) / stride_px + 0.5),
          static_cast<float>((camera.cy - half) / stride_px + 0.5)};
}

DepthAligner::DepthAligner(const CameraConfig& camera, const RefinementConfig& refinement, double depth_noise_coeff,
                           double depth_units_per_m)
    : config_(refinement),
      depth_noise_coeff_(depth_noise_coeff),
      quantum_sigma_m_(1.0 / (depth_units_per_m * std::sqrt(12.0))),
      grid_(grid_intrinsics(camera, refinement.stride_px)),
      associate_(simd::active_kernels().associate),
      units_per_m_(depth_units_per_m),
      unit_gradient_prev_(kRoundingBuckets),
      unit_gradient_curr_(kRoundingBuckets),
      unit_mark_prev_(kRoundingBuckets, 0u),
      unit_mark_curr_(kRoundingBuckets, 0u) {
  shared_prev_.reserve(kRoundingBuckets);
  shared_curr_.reserve(kRoundingBuckets);
}

void DepthAligner::align(const DepthCloud& prev, const DepthCloud& curr, const Eigen::Isometry3d& seed,
                         DepthAlignment& out) {
  out = DepthAlignment{};
  if (prev.empty() || curr.empty() || prev.cols != curr.cols || prev.rows != curr.rows) return;
  cell_grid_ = std::max(1, static_cast<int>(std::lround(config_.cell_px / config_.stride_px)));
  cells_x_ = (curr.cols + cell_grid_ - 1) / cell_grid_;
  const int cells_y = (curr.rows + cell_grid_ - 1) / cell_grid_;
  cell_gradient_.resize(static_cast<size_t>(cells_x_ * cells_y));
  cell_count_.resize(cell_gradient_.size());
  const size_t capacity = curr.point.size();
  if (terms_.size() < capacity) terms_.resize(capacity), term_cells_.resize(capacity), scaled_.reserve(capacity);
  term_count_ = 0;

  Eigen::Isometry3d T = seed;
  NormalEquations eq;
  // The association kernel's constants; the clouds' grids are pinhole (DepthCloudBuilder): no
  // lens model, the projection rounded to the nearest sample by truncating from + 0.5.
  simd::AssociateInput in{};
  in.prev_point = prev.point.front().data();
  in.prev_normal = prev.normal.front().data();
  in.cols = prev.cols;
  in.rows = prev.rows;
  in.fx = grid_[0], in.fy = grid_[1], in.cx = grid_[2], in.cy = grid_[3];
  in.max_d2 = static_cast<float>(config_.max_distance_m * config_.max_distance_m);
  in.coeff = static_cast<float>(depth_noise_coeff_);
  in.floor2 = static_cast<float>(2 * quantum_sigma_m_ * quantum_sigma_m_);
  // The cells' sums serve the covariance alone, at the last linearisation: summed on the last
  // step, or after the loop where an earlier step ended it.
  bool cells_summed = false;
  for (int it = 0; it < config_.iterations; ++it) {
    associate(curr, T, it, in);
    if (static_cast<int>(term_count_) < config_.min_points) return;
    cells_summed = it == config_.iterations - 1;
    eq = cells_summed ? weighted_normal_equations<true>() : weighted_normal_equations<false>();
    if (eq.used < config_.min_points) return;
    const Eigen::LDLT<Matrix6d> ldlt(eq.H);
    if (ldlt.info() != Eigen::Success) return;
    const Vector6d step = -ldlt.solve(eq.b);
    if (!step.allFinite()) return;
    T = T * transform_from_xi(step);
    if (step.head<3>().norm() < kStepTranslationM && step.tail<3>().norm() < kStepRotationRad) break;
  }
  if (!cells_summed) sum_cells(eq);
  Matrix6d H_inv;
  if (!cluster_covariance(eq, out, H_inv)) return;
  add_shared_rounding(prev, curr, eq, H_inv, out);
  out.T_prev_curr = T;
  out.points = eq.used;
  out.ok = out.constrained > 0 && out.covariance.allFinite();
  if (out.ok) out.depth_noise_coeff = residual_noise_coeff(prev, curr, T);
}

void DepthAligner::associate(const DepthCloud& curr, const Eigen::Isometry3d& T, int it, simd::AssociateInput& in) {
  // The associations and their residuals at T, in single precision: a few thousand points,
  // each to well below the depth's own resolution (the sums are kept in double).
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) in.r[3 * row + col] = static_cast<float>(T.linear()(row, col));
    in.t[row] = static_cast<float>(T.translation()(row));
  }
  // Every step but the last takes every other point (a checkerboard, alternating): they only
  // have to come near; the last one, which the covariance is computed at, takes them all.
  const bool last = it == config_.iterations - 1;
  in.step = last ? 1 : 2;
  term_count_ = 0;
  // In registers: the stores into term_cells_ below could otherwise alias them.
  const int cell_grid = cell_grid_, cells_x = cells_x_;
  for (int j = 0; j < curr.rows; ++j) {
    const int first = last ? 0 : ((j + it) & 1);
    in.first_index = j * curr.cols + first;
    in.curr = curr.point[static_cast<size_t>(in.first_index)].data();
    in.n = (curr.cols - first + in.step - 1) / in.step;
    const auto found = static_cast<size_t>(associate_(in, terms_.data() + term_count_));
    const int cell_row = (j / cell_grid) * cells_x;
    const size_t end = term_count_ + found;
    for (size_t k = term_count_; k < end; ++k)
      term_cells_[k] = cell_row + (terms_[k].curr_index - j * curr.cols) / cell_grid;
    term_count_ = end;
  }
}

template <bool kCells>
DepthAligner::NormalEquations DepthAligner::weighted_normal_equations() {
  const std::span<const simd::Association> terms(terms_.data(), term_count_);
  // Tukey's biweight on the normalised residuals, its scale their median absolute deviation
  // (over every 8th association: plenty for a median): associations across a crease or an
  // occlusion edge weigh nothing, whatever the sensor's noise.
  scaled_.clear();
  for (size_t k = 0; k < terms.size(); k += 8) scaled_.push_back(terms[k].r * terms[k].r * terms[k].w);
  const auto mid = scaled_.begin() + static_cast<std::ptrdiff_t>(scaled_.size() / 2);
  std::nth_element(scaled_.begin(), mid, scaled_.end());
  const double scale2 = 1.4826 * 1.4826 * static_cast<double>(*mid);
  const double cutoff2 = 4.685 * 4.685 * std::max(scale2, 1e-24);

  // The sums in locals, not in the returned object: stores into cell_gradient_ and cell_count_
  // could alias its fields and keep them out of registers.
  std::array<double, 21> h{};  // the lower triangle of H, row by row
  Vector6d b = Vector6d::Zero();
  int used = 0;
  if constexpr (kCells) {
    std::fill(cell_gradient_.begin(), cell_gradient_.end(), Vector6d::Zero());
    std::fill(cell_count_.begin(), cell_count_.end(), 0);
  }
  double sum_wr2 = 0, sum_weight = 0;
  // No cutoff below the depth's quantisation: exact depth has residuals of rounding only,
  // whose median says nothing of which associations are wrong.
  const double floor_r2 = 4.685 * 4.685 * quantum_sigma_m_ * quantum_sigma_m_;
  for (size_t a = 0; a < terms.size(); ++a) {
    const simd::Association& term = terms[a];
    const double r2 = static_cast<double>(term.r) * term.r;
    // robust_share()'s rule, written out: through a helper the ARM build's refine stage cost 5 % more.
    const double u2 = r2 / std::max(cutoff2 / term.w, floor_r2);
    if (u2 >= 1) continue;
    const double robust = (1 - u2) * (1 - u2);
    const double w = robust * term.w;
    Vector6d J;
    for (int e = 0; e < 6; ++e) J(e) = term.j[e];
    for (int row = 0, at = 0; row < 6; ++row)
      for (int col = 0; col <= row; ++col, ++at) h[static_cast<size_t>(at)] += w * J(row) * J(col);
    const double wr = w * term.r;
    b += wr * J;
    sum_wr2 += wr * term.r;
    sum_weight += robust;
    if constexpr (kCells) {
      const auto cell = static_cast<size_t>(term_cells_[a]);
      cell_gradient_[cell] += wr * J;
      ++cell_count_[cell];
    }
    ++used;
  }
  NormalEquations eq;
  for (int row = 0, at = 0; row < 6; ++row)
    for (int col = 0; col <= row; ++col, ++at) eq.H(row, col) = eq.H(col, row) = h[static_cast<size_t>(at)];
  eq.b = b;
  eq.used = used;
  eq.s2 = sum_wr2 / std::max(sum_weight - 6, 1.0);
  eq.cutoff2 = cutoff2;
  eq.floor_r2 = floor_r2;
  return eq;
}

double DepthAligner::robust_share(const simd::Association& term, const NormalEquations& eq) {
  const double u2 = static_cast<double>(term.r) * term.r / std::max(eq.cutoff2 / term.w, eq.floor_r2);
  return u2 < 1 ? (1 - u2) * (1 - u2) : 0.0;
}

float DepthAligner::term_weight(const simd::Association& term, const NormalEquations& eq) {
  return static_cast<float>(robust_share(term, eq) * term.w);
}

void DepthAligner::sum_cells(const NormalEquations& eq) {
  // weighted_normal_equations<true>'s cell sums, term for term in the same arithmetic.
  std::fill(cell_gradient_.begin(), cell_gradient_.end(), Vector6d::Zero());
  std::fill(cell_count_.begin(), cell_count_.end(), 0);
  for (size_t a = 0; a < term_count_; ++a) {
    const simd::Association& term = terms_[a];
    const double robust = robust_share(term, eq);
    if (!(robust > 0)) continue;
    const double wr = robust * term.w * term.r;
    Vector6d J;
    for (int e = 0; e < 6; ++e) J(e) = term.j[e];
    const auto cell = static_cast<size_t>(term_cells_[a]);
    cell_gradient_[cell] += wr * J;
    ++cell_count_[cell];
  }
}

bool DepthAligner::cluster_covariance(const NormalEquations& eq, DepthAlignment& out, Matrix6d& H_inv) const {
  // The covariance at the last linearisation: cells as clusters of correlated residuals.
  Matrix6d spread = Matrix6d::Zero();
  int cells = 0;
  for (size_t c = 0; c < cell_gradient_.size(); ++c)
    if (cell_count_[c] > 0) {
      spread += cell_gradient_[c] * cell_gradient_[c].transpose();
      ++cells;
    }
  if (cells < kMinCells) return false;
  // Eigen-decomposed: a direction the surfaces leave free (a plane's sliding, a corridor's
  // length) carries no information, however small the residuals (exact depth).
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(eq.H);
  if (eig.info() != Eigen::Success || !(eig.eigenvalues().maxCoeff() > 0)) return false;
  const double max_eigenvalue = eig.eigenvalues().maxCoeff();
  int k = 0;
  Matrix6d basis = Matrix6d::Zero();
  Eigen::Matrix<double, 6, 1> inv = Eigen::Matrix<double, 6, 1>::Zero();
  for (int e = 5; e >= 0; --e)  // largest first
    if (eig.eigenvalues()(e) > kMinRelativeInformation * max_eigenvalue) {
      basis.col(k) = eig.eigenvectors().col(e);
      inv(k) = 1.0 / eig.eigenvalues()(e);
      ++k;
    }
  H_inv = basis * inv.asDiagonal() * basis.transpose();  // pseudo-inverse within the basis
  // The clusters' spread (with the small-sample correction) and, so that few cells cannot leave
  // a direction without variance, the independent-residual term weighted by 6 / cells.
  const double n_cells = cells;
  out.covariance = H_inv * spread * H_inv * (n_cells / (n_cells - 1)) + H_inv * (eq.s2 * 6.0 / n_cells);
  out.covariance = 0.5 * (out.covariance + out.covariance.transpose());
  out.basis = basis;
  out.constrained = k;
  return true;
}

void DepthAligner::add_shared_rounding(const DepthCloud& prev, const DepthCloud& curr, const NormalEquations& eq,
                                       const Matrix6d& H_inv, DepthAlignment& out) {
  // A glance first, at every kRoundingGlance-th association: where the depth's noise swamps
  // its rounding (a Kinect's millimetres against 0.2 mm units) the shared part changes the
  // covariance by less than kRoundingNegligible in any direction and is left at that; where
  // it does not (exact depth), every association is read.
  Matrix6d part = H_inv * shared_rounding_spread(prev, curr, eq, kRoundingGlance) * H_inv;
  const int k = out.constrained;
  using Square = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;
  const Square V = out.basis.leftCols(k);
  const Eigen::LDLT<Square> base(V.transpose() * out.covariance * V);
  if (base.info() != Eigen::Success) return;
  // Its share in the whitened covariance: the trace bounds the largest direction's.
  const double share = base.solve(V.transpose() * part * V).trace();
  if (!(share <= kRoundingNegligible)) part = H_inv * shared_rounding_spread(prev, curr, eq, 1) * H_inv;
  out.covariance += 0.5 * (part + part.transpose());
}

Matrix6d DepthAligner::shared_rounding_spread(const DepthCloud& prev, const DepthCloud& curr, const NormalEquations& eq,
                                               int every) {
  // Every sample read as one depth unit carries one rounding error, however many share it. On
  // exact depth a wall square to the camera is one unit across thousands of samples (a wall
  // turned about the vertical, one unit down each column): their residuals all move with it,
  // so they show nothing of it, and counted as independent it is a thousand times too small.
  // A depth error e moves a point X by e X / Z, the residual by e n . X / Z (taken at the
  // target for both frames: the two points lie a pair's motion apart). Each unit's weighted
  // gradient is summed, for each frame apart; their spread times the rounding's variance is
  // what the estimate takes from them (src/pipeline/MEASUREMENTS.md#shared-rounding). A unit
  // read once is left out: the weights already count its rounding as independent noise.
  unit_generation_ += 2;  // a bucket's mark: this generation once read, + 1 once shared
  if (unit_generation_ < 2) {  // wrapped: every mark is stale
    std::fill(unit_mark_prev_.begin(), unit_mark_prev_.end(), 0u);
    std::fill(unit_mark_curr_.begin(), unit_mark_curr_.end(), 0u);
    unit_generation_ = 2;
  }
  shared_prev_.clear();
  shared_curr_.clear();
  const auto units_per_m = static_cast<float>(units_per_m_);
  const auto add = [&](float depth_m, float scale, const float* j, std::vector<Eigen::Matrix<float, 6, 1>>& sums,
                       std::vector<std::uint32_t>& marks, std::vector<int>& shared) {
    const auto b = static_cast<size_t>(static_cast<int>(depth_m * units_per_m + 0.5f) & (kRoundingBuckets - 1));
    Eigen::Matrix<float, 6, 1>& g = sums[b];
    if (marks[b] == unit_generation_) {  // its second sample: a shared unit
      marks[b] = unit_generation_ + 1;
      shared.push_back(static_cast<int>(b));
    } else if (marks[b] != unit_generation_ + 1) {  // its first
      marks[b] = unit_generation_;
      g.setZero();
    }
    for (int e = 0; e < 6; ++e) g(e) += scale * j[e];
  };
  for (size_t k = 0; k < term_count_; k += static_cast<size_t>(every)) {
    const simd::Association& term = terms_[k];
    const float w = term_weight(term, eq);
    if (!(w > 0)) continue;
    const auto pi = static_cast<size_t>(term.prev_index);
    const Eigen::Vector3f& q = prev.point[pi];
    const float along = w * prev.normal[pi].dot(q) / q.z();
    add(curr.raw_depth[static_cast<size_t>(term.curr_index)], along, term.j, unit_gradient_curr_, unit_mark_curr_,
        shared_curr_);
    add(prev.raw_depth[pi], -along, term.j, unit_gradient_prev_, unit_mark_prev_, shared_prev_);
  }
  // The lower triangle only (rankUpdate): on exact depth thousands of units are shared.
  Matrix6d spread = Matrix6d::Zero();
  for (int b : shared_prev_)
    spread.selfadjointView<Eigen::Lower>().rankUpdate(unit_gradient_prev_[static_cast<size_t>(b)].cast<double>());
  for (int b : shared_curr_)
    spread.selfadjointView<Eigen::Lower>().rankUpdate(unit_gradient_curr_[static_cast<size_t>(b)].cast<double>());
  spread = spread.selfadjointView<Eigen::Lower>();
  // Read at every `every`-th association: each unit's sum is that share of its whole.
  return spread * (static_cast<double>(every * every) * quantum_sigma_m_ * quantum_sigma_m_);
}

double DepthAligner::residual_noise_coeff(const DepthCloud& prev, const DepthCloud& curr, const Eigen::Isometry3d& T) {
  // A depth error e (sigma c Z^2) moves a point X by e X / Z, so r = n . (e_curr X_curr / Z_curr
  // - e_prev X_prev / Z_prev): var r = c^2 g + rounding, g = Z_curr^4 (n . X_curr / Z_curr)^2 +
  // Z_prev^4 (n . X_prev / Z_prev)^2. Every 8th association (the last iteration's, residuals at
  // its start, which its step barely moves).
  const Eigen::Matrix3f R = T.linear().cast<float>();
  const Eigen::Vector3f t = T.translation().cast<float>();
  const bool averaged = !prev.averaged.empty() || !curr.averaged.empty();
  const double rounding2 = 2 * quantum_sigma_m_ * quantum_sigma_m_;
  scaled_.clear();
  for (size_t k = 0; k < term_count_; k += 8) {
    const simd::Association& term = terms_[k];
    // Averaged samples are read at their own pixels' depths again: the coefficient is the
    // sensor's per pixel, as the keypoints read it.
    const auto ci = static_cast<size_t>(term.curr_index), pi = static_cast<size_t>(term.prev_index);
    const Eigen::Vector3f p = averaged ? Eigen::Vector3f(curr.point[ci] * (curr.raw_depth[ci] / curr.point[ci].z())) : curr.point[ci];
    const Eigen::Vector3f target =
        averaged ? Eigen::Vector3f(prev.point[pi] * (prev.raw_depth[pi] / prev.point[pi].z())) : prev.point[pi];
    const Eigen::Vector3f& n = prev.normal[pi];
    const float r = averaged ? n.dot(R * p + t - target) : term.r;
    const float along_curr = n.dot(R * p) / p.z(), along_prev = n.dot(target) / target.z();
    const float z2_curr = p.z() * p.z(), z2_prev = target.z() * target.z();
    const double g = static_cast<double>(z2_curr * z2_curr * along_curr * along_curr +
                                         z2_prev * z2_prev * along_prev * along_prev);
    if (!(g > 0)) continue;
    scaled_.push_back(static_cast<float>((static_cast<double>(r) * r - kChi2Median1 * rounding2) / g));
  }
  if (scaled_.size() < 16) return -1;
  const auto mid = scaled_.begin() + static_cast<std::ptrdiff_t>(scaled_.size() / 2);
  std::nth_element(scaled_.begin(), mid, scaled_.end());
  return std::sqrt(std::max(static_cast<double>(*mid), 0.0) / kChi2Median1);
}

DepthNoiseEstimate::DepthNoiseEstimate(double prior)
    : c_(prior, {.averaged_readings = 10,  // = 1 / kNoiseRate: where the two rules meet
                 .geometric = true,
                 .gain = 1,
                 .max_step = kNoiseRate,
                 .min = kNoiseMin,
                 .max = kNoiseMax}) {}

AlignmentTrust::AlignmentTrust(const RefinementConfig& config)
    : k_t_(config.sigma_scale_prior),
      k_r_(config.sigma_scale_prior),
      rate_(config.sigma_scale_rate),
      max_(config.sigma_scale_max) {}

Matrix6d AlignmentTrust::scaled(const Matrix6d& depth_cov) const {
  Vector6d k;
  k << k_t_, k_t_, k_t_, k_r_, k_r_, k_r_;
  return k.asDiagonal() * depth_cov * k.asDiagonal();
}

void AlignmentTrust::update(const Vector6d& d, const Matrix6d& feature_cov, const Matrix6d& depth_cov,
                            const Eigen::Matrix3d& lag_rotation_cov) {
  if (!d.allFinite() || !feature_cov.allFinite() || !depth_cov.allFinite()) return;
  window_[static_cast<size_t>(next_)] = {d, feature_cov, depth_cov};
  next_ = (next_ + 1) % kWindow;
  filled_ = std::min(filled_ + 1, kWindow);
  Vector6d sum_d = Vector6d::Zero();
  Matrix6d sum_f = Matrix6d::Zero(), sum_depth = Matrix6d::Zero();
  for (int i = 0; i < filled_; ++i) {
    sum_d += window_[static_cast<size_t>(i)].d;
    sum_f += window_[static_cast<size_t>(i)].feature_cov;
    sum_depth += window_[static_cast<size_t>(i)].depth_cov;
  }
  // The NEES of a difference in one 3-D block (0: translation, 3: rotation).
  const auto nees3 = [&](const Vector6d& v, const Matrix6d& C, int at) {
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(C.block<3, 3>(at, at));
    if (ldlt.info() != Eigen::Success) return 3.0;
    return v.segment<3>(at).dot(ldlt.solve(v.segment<3>(at)));
  };
  Matrix6d pair_expected = feature_cov + scaled(depth_cov);
  pair_expected.bottomRightCorner<3, 3>() += lag_rotation_cov;
  // The lag's share telescopes over a window (the rate at its end less the rate at its start).
  Matrix6d window_expected = sum_f + scaled(sum_depth);
  window_expected.bottomRightCorner<3, 3>() += lag_rotation_cov;
  // A multiplicative step towards E[NEES] = 3 per block, for the pair and for the window's
  // sum, whichever is larger: bounded per pair, so one wild pair (a diverged alignment, a
  // wrong feature fit) moves k by a few per cent at most.
  const auto step = [&](double& k, int at) {
    const double nees = std::max(nees3(d, pair_expected, at), filled_ == kWindow ? nees3(sum_d, window_expected, at) : 0.0);
    const double factor = std::clamp(1.0 + rate_ * (nees / 3.0 - 1.0), 1.0 - rate_, 1.0 + 2 * rate_);
    k = std::clamp(k * std::sqrt(factor), 1.0, max_);
  };
  step(k_t_, 0);
  step(k_r_, 3);
}

DepthLagEstimate::DepthLagEstimate(const RefinementConfig& config)
    : sum_rr_(kLagPriorWeight), max_s_(config.max_depth_lag_s) {}

void DepthLagEstimate::update(const Eigen::Vector3d& d_rotation, const Eigen::Vector3d& delta_rate,
                              double delta_rate_variance) {
  if (!d_rotation.allFinite() || !delta_rate.allFinite() || !std::isfinite(delta_rate_variance)) return;
  constexpr double keep = 1.0 - 1.0 / kLagMemoryPairs;
  sum_dr_ = keep * sum_dr_ + d_rotation.dot(delta_rate);
  // A rate change no larger than its own noise says nothing: it adds nothing to either sum.
  const double signal = delta_rate.squaredNorm() - delta_rate_variance;
  sum_rr_ = keep * sum_rr_ + std::max(signal, 0.0);
  sum_rr_ = std::max(sum_rr_, kLagPriorWeight * keep);  // never below a few pairs' worth
  lag_s_ = std::clamp(-sum_dr_ / sum_rr_, -max_s_, max_s_);
  const double noise_per_axis = delta_rate_variance / 3.0;
  moment_ = keep * moment_ + (1 - keep) * (delta_rate * delta_rate.transpose() -
                                           noise_per_axis * Eigen::Matrix3d::Identity());
}

Eigen::Matrix3d DepthLagEstimate::rotation_covariance() const {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(moment_);
  if (eig.info() != Eigen::Success) return Eigen::Matrix3d::Zero();
  const Eigen::Matrix3d psd =
      eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
  return lag_s_ * lag_s_ * psd;
}

bool fuse_estimates(const Eigen::Isometry3d& a, const Matrix6d& cov_a, const Eigen::Isometry3d& b,
                    const Matrix6d& cov_b, const Matrix6d& basis_b, int k, Eigen::Isometry3d& fused,
                    Matrix6d& fused_cov, const Matrix6d* b_error_cov) {
  if (k < 1 || k > 6) return false;
  // Fixed-capacity matrices: the pair stage allocates nothing.
  using Basis = Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, 6>;
  using Square = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;
  using Column = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 6, 1>;
  const Basis V = basis_b.leftCols(k);
  // Within b's directions: its measurement z = V^T d of the difference d, noise V^T cov_b V.
  const Column z = V.transpose() * right_perturbation_between(a, b);
  const Square S = V.transpose() * (cov_a + cov_b) * V;
  const Eigen::LDLT<Square> ldlt(S);
  if (ldlt.info() != Eigen::Success) return false;
  if (!(z.dot(ldlt.solve(z)) <= kAgreementGate[static_cast<size_t>(k - 1)])) return false;
  // A Kalman update of a's perturbation by the measurement: gain K = cov_a V S^-1.
  const Basis K = ldlt.solve(V.transpose() * cov_a).transpose();
  const Vector6d x = K * z;
  if (!x.allFinite()) return false;
  fused = a * transform_from_xi(x);
  if (b_error_cov) {
    // x = G d to first order, d = b - a: a's error enters as (I - G), b's as G.
    const Matrix6d G = K * V.transpose();
    const Matrix6d keep = Matrix6d::Identity() - G;
    fused_cov = keep * cov_a * keep.transpose() + G * *b_error_cov * G.transpose();
  } else {
    fused_cov = cov_a - K * (V.transpose() * cov_a);
  }
  fused_cov = 0.5 * (fused_cov + fused_cov.transpose());
  return fused_cov.allFinite();
}

}  // namespace rgbdo
