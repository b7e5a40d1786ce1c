#include "rgbd_odometry/pipeline/covariance.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "rgbd_odometry/pipeline/noise_model.hpp"
#include "rgbd_odometry/core/umeyama.hpp"

namespace rgbdo {

bool is_valid_covariance(const Matrix6d& c) {
  if (!c.allFinite()) return false;
  if (!c.isApprox(c.transpose(), 1e-9)) return false;
  const Eigen::LLT<Matrix6d> llt(c);
  return llt.info() == Eigen::Success;
}

double PerturbationCovariance::variance_factor(const std::vector<Eigen::Vector3d>& prev,
                                               const std::vector<Eigen::Vector3d>& curr,
                                               const std::vector<PointNoise>& prev_noise,
                                               const std::vector<PointNoise>& curr_noise,
                                               const Eigen::Isometry3d& T_prev_curr) {
  const size_t n = prev.size();
  if (n < 3) return 1.0;
  const Eigen::Matrix3d R = T_prev_curr.linear();
  double sum = 0;
  for (size_t k = 0; k < n; ++k) {
    const Eigen::Matrix3d C = prev_noise[k].covariance() + R * curr_noise[k].covariance() * R.transpose();
    const Eigen::Vector3d r = prev[k] - T_prev_curr * curr[k];
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(C);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0)) continue;  // a noiseless point says nothing
    sum += r.dot(ldlt.solve(r));
  }
  // 3n residual components, 6 parameters.
  return std::max(1.0, sum / (3.0 * static_cast<double>(n) - 6.0));
}

Vector6d PerturbationCovariance::timing_gradient(const std::vector<Eigen::Vector3d>& prev,
                                                 const std::vector<Eigen::Vector3d>& curr,
                                                 const std::vector<PointNoise>& noise, bool of_prev) {
  rates_.resize(noise.size());
  for (size_t k = 0; k < noise.size(); ++k) rates_[k] = noise[k].depth_rate_mps;
  return depth_shift_response(prev, curr, rates_, of_prev);
}

Vector6d PerturbationCovariance::depth_shift_response(const std::vector<Eigen::Vector3d>& prev,
                                                      const std::vector<Eigen::Vector3d>& curr,
                                                      std::span<const double> rates_mps, bool of_prev) {
  // Central difference over +-1 ms: the fit is linear in the depths to far better than that.
  constexpr double h = 1e-3;
  const std::vector<Eigen::Vector3d>& moving = of_prev ? prev : curr;
  Vector6d xi[2];
  for (int side = 0; side < 2; ++side) {
    const double dt = side == 0 ? h : -h;
    moved_.resize(moving.size());
    for (size_t k = 0; k < moving.size(); ++k)
      moved_[k] = moving[k] * (1.0 + dt * rates_mps[k] / moving[k].z());  // along the ray
    Eigen::Isometry3d T;
    if (!fit_rigid(of_prev ? curr : moved_, of_prev ? moved_ : prev, weights_, T)) return Vector6d::Zero();
    xi[side] = xi_from_transform(T);
  }
  return (xi[0] - xi[1]) / (2 * h);
}

Matrix6d PerturbationCovariance::depth_latency_response(const std::vector<Eigen::Vector3d>& prev,
                                                        const std::vector<Eigen::Vector3d>& curr) {
  // Column i: the camera moving at unit rate i (m/s or rad/s) changes a static point's depth
  // at dZ/dt = -(v + w x P)_z; the current frame's depths are read that much late, per second.
  Matrix6d response = Matrix6d::Zero();
  if (weights_.size() != curr.size() || prev.size() != curr.size()) return response;
  rates_.resize(curr.size());
  for (int i = 0; i < 6; ++i) {
    Eigen::Vector3d v = Eigen::Vector3d::Zero(), w = Eigen::Vector3d::Zero();
    (i < 3 ? v : w)(i % 3) = 1.0;
    for (size_t k = 0; k < curr.size(); ++k) rates_[k] = -(v + w.cross(curr[k])).z();
    response.col(i) = depth_shift_response(prev, curr, rates_, false);
  }
  return response;
}

PerturbationCovariance::PerturbationCovariance(const CovarianceConfig& config, int max_points)
    : config_(config),
      kernels_(simd::active_kernels()),
      padded_perturbations_((config.perturbations + simd::kPerturbationLanes - 1) / simd::kPerturbationLanes *
                            simd::kPerturbationLanes) {
  reserve(max_points);
  sums_.resize(static_cast<size_t>(15 * padded_perturbations_));
  samples_.reserve(static_cast<size_t>(config.perturbations));
}

void PerturbationCovariance::reserve(int points) {
  for (auto* v : {&sx_, &sy_, &sz_, &dx_, &dy_, &dz_, &ssx_, &ssy_, &rsx_, &rsy_, &rsz_, &sdx_, &sdy_, &rdx_, &rdy_,
                  &rdz_, &w_})
    v->reserve(static_cast<size_t>(points));
  weights_.reserve(static_cast<size_t>(points));
  paper_prev_.reserve(static_cast<size_t>(points));
  paper_curr_.reserve(static_cast<size_t>(points));
  moved_.reserve(static_cast<size_t>(points));
  rates_.reserve(static_cast<size_t>(points));
  cell_.reserve(static_cast<size_t>(points));
  // A pair reaching a cell no earlier pair reached must not allocate: room for kMaxCells
  // (the default 160-px cells of a 640 x 480 image are 12).
  const auto P = static_cast<size_t>(padded_perturbations_);
  cell_weight_.reserve(kMaxCells * P);
  cell_total_.reserve(kMaxCells);
  perturbation_weight_.reserve(P);
}

bool PerturbationCovariance::estimate(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                                      const Eigen::Isometry3d& T_prev_curr, Rng& rng, Matrix6d& covariance) {
  paper_prev_.clear();
  paper_curr_.clear();
  for (size_t k = 0; k < prev.size() && k < curr.size(); ++k) {
    paper_prev_.push_back(paper_point_noise(prev[k], config_.depth_noise_coeff));
    paper_curr_.push_back(paper_point_noise(curr[k], config_.depth_noise_coeff));
  }
  return estimate(prev, curr, paper_prev_, paper_curr_, {}, T_prev_curr, 0.0, rng, covariance);
}

bool PerturbationCovariance::estimate(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                                      const std::vector<PointNoise>& prev_noise,
                                      const std::vector<PointNoise>& curr_noise, std::span<const std::uint16_t> cells,
                                      const Eigen::Isometry3d& T_prev_curr, double timing_sigma_s, Rng& rng,
                                      Matrix6d& covariance) {
  const size_t n = prev.size();
  samples_.clear();
  if (n < 3 || curr.size() != n || prev_noise.size() != n || curr_noise.size() != n ||
      (!cells.empty() && cells.size() != n))
    return false;
  const double s0_squared =
      config_.residual_variance_factor ? variance_factor(prev, curr, prev_noise, curr_noise, T_prev_curr) : 1.0;
  const Centres centres = centre_clouds(prev, curr, prev_noise, curr_noise, std::sqrt(s0_squared));
  draw_cell_weights(cells, rng);
  if (!fit_perturbations(centres, rng)) return false;

  covariance = sample_covariance(samples_);
  last_timing_.setZero();
  if (timing_sigma_s > 0) {
    const Vector6d g_prev = timing_gradient(prev, curr, prev_noise, true);
    const Vector6d g_curr = timing_gradient(prev, curr, curr_noise, false);
    last_timing_ = timing_sigma_s * timing_sigma_s * (g_prev * g_prev.transpose() + g_curr * g_curr.transpose());
    covariance += last_timing_;
  }
  covariance *= config_.scale;
  covariance = 0.5 * (covariance + covariance.transpose());  // exact symmetry for consumers
  return is_valid_covariance(covariance);
}

PerturbationCovariance::Centres PerturbationCovariance::centre_clouds(const std::vector<Eigen::Vector3d>& prev,
                                                                      const std::vector<Eigen::Vector3d>& curr,
                                                                      const std::vector<PointNoise>& prev_noise,
                                                                      const std::vector<PointNoise>& curr_noise,
                                                                      double noise_scale) {
  // Centre both clouds on their weighted centroids (in double) so that the float sums hold
  // small numbers and the per-perturbation cross-covariance loses no precision.
  const size_t n = prev.size();
  for (auto* v : {&sx_, &sy_, &sz_, &dx_, &dy_, &dz_, &ssx_, &ssy_, &rsx_, &rsy_, &rsz_, &sdx_, &sdy_, &rdx_, &rdy_,
                  &rdz_, &w_})
    v->resize(n);
  weights_.resize(n);
  double total = 0;
  Centres c;
  for (size_t k = 0; k < n; ++k) {
    const double w = pair_weight(prev[k], curr[k], config_.depth_noise_coeff);  // the same weights as the fit's
    weights_[k] = w;
    total += w;
    c.curr += w * curr[k];
    c.prev += w * prev[k];
  }
  c.curr /= total;
  c.prev /= total;
  const auto f = [](double x) { return static_cast<float>(x); };
  for (size_t k = 0; k < n; ++k) {
    const Eigen::Vector3d s = curr[k] - c.curr, d = prev[k] - c.prev;
    const Eigen::Vector2d ls = noise_scale * curr_noise[k].lateral, ld = noise_scale * prev_noise[k].lateral;
    const Eigen::Vector3d rs = noise_scale * curr_noise[k].ray, rd = noise_scale * prev_noise[k].ray;
    sx_[k] = f(s.x()), sy_[k] = f(s.y()), sz_[k] = f(s.z());
    dx_[k] = f(d.x()), dy_[k] = f(d.y()), dz_[k] = f(d.z());
    ssx_[k] = f(ls.x()), ssy_[k] = f(ls.y());
    rsx_[k] = f(rs.x()), rsy_[k] = f(rs.y()), rsz_[k] = f(rs.z());
    sdx_[k] = f(ld.x()), sdy_[k] = f(ld.y());
    rdx_[k] = f(rd.x()), rdy_[k] = f(rd.y()), rdz_[k] = f(rd.z());
    w_[k] = f(weights_[k] / total);
  }
  return c;
}

void PerturbationCovariance::draw_cell_weights(std::span<const std::uint16_t> cells, Rng& rng) {
  // Each perturbation re-weights the image cells by independent Exp(1) draws (a Bayesian
  // bootstrap of the inlier set by cell); one cell of weight 1 when not resampling.
  const size_t n = w_.size();
  const size_t P = static_cast<size_t>(padded_perturbations_);
  int cell_count = 1;
  cell_.assign(n, 0);
  for (size_t k = 0; k < cells.size(); ++k) {
    cell_[k] = cells[k];
    cell_count = std::max(cell_count, cells[k] + 1);
  }
  cell_weight_.assign(static_cast<size_t>(cell_count) * P, 1.0f);
  if (!cells.empty())
    for (float& g : cell_weight_) g = static_cast<float>(-std::log(1.0 - rng.uniform01()));  // uniform01 < 1
  cell_total_.assign(static_cast<size_t>(cell_count), 0.0);
  for (size_t k = 0; k < n; ++k) cell_total_[cell_[k]] += w_[k];
  perturbation_weight_.assign(P, 0.0);
  for (size_t cc = 0; cc < static_cast<size_t>(cell_count); ++cc)
    for (size_t p = 0; p < P; ++p) perturbation_weight_[p] += cell_total_[cc] * cell_weight_[cc * P + p];
}

bool PerturbationCovariance::fit_perturbations(const Centres& centres, Rng& rng) {
  const size_t P = static_cast<size_t>(padded_perturbations_);
  simd::PerturbationInput in;
  in.points = static_cast<int>(w_.size());
  in.perturbations = padded_perturbations_;
  in.sx = sx_.data(), in.sy = sy_.data(), in.sz = sz_.data();
  in.dx = dx_.data(), in.dy = dy_.data(), in.dz = dz_.data();
  in.sigma_sx = ssx_.data(), in.sigma_sy = ssy_.data();
  in.ray_sx = rsx_.data(), in.ray_sy = rsy_.data(), in.ray_sz = rsz_.data();
  in.sigma_dx = sdx_.data(), in.sigma_dy = sdy_.data();
  in.ray_dx = rdx_.data(), in.ray_dy = rdy_.data(), in.ray_dz = rdz_.data();
  in.w = w_.data();
  in.cell = cell_.data();
  in.cell_weight = cell_weight_.data();
  in.seed = (static_cast<std::uint64_t>(rng.next_u32()) << 32) | rng.next_u32();
  simd::PerturbationSums out;
  for (int j = 0; j < 3; ++j) {
    out.s[j] = sums_.data() + static_cast<size_t>(j) * P;
    out.d[j] = sums_.data() + static_cast<size_t>(3 + j) * P;
  }
  for (int e = 0; e < 9; ++e) out.m[e] = sums_.data() + static_cast<size_t>(6 + e) * P;
  kernels_.perturbation_sums(in, out);

  for (int p = 0; p < config_.perturbations; ++p) {
    Eigen::Vector3d s, d;
    Eigen::Matrix3d m;
    for (int j = 0; j < 3; ++j) {
      s(j) = out.s[j][p];
      d(j) = out.d[j][p];
    }
    for (int e = 0; e < 9; ++e) m(e / 3, e % 3) = out.m[e][p];
    const double weight_sum = perturbation_weight_[static_cast<size_t>(p)];
    Eigen::Isometry3d T;  // maps centred current points onto centred previous ones
    if (!fit_from_sums(s, d, m, weight_sum, T)) return false;
    T.translation() += centres.prev - T.linear() * centres.curr;
    samples_.push_back(xi_from_transform(T));
  }
  return true;
}

}  // namespace rgbdo
