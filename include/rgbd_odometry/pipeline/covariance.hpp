#pragma once
// Stage 5: the odometry covariance by statistical perturbation (Willis & Brink Sec. III-C).
// The inlier point pairs are perturbed N times with the sensor noise model, each perturbed
// pair of clouds is aligned again, and the unbiased sample covariance of the N parameter
// vectors xi = (t, rotation vector) is the estimate, multiplied by the configured scale.
//
// Each point is perturbed with its own noise (pipeline/noise_model.hpp: the physical model by
// default, the paper's for comparison). All N perturbations are generated and accumulated
// together by the active SIMD kernel (rgbd_odometry/simd/perturb.hpp: vectorised Gaussian
// noise, structure-of-arrays weighted sums of the centred clouds), then each perturbation's
// motion follows from its sums by one fixed-size 3x3 solve (fit_from_sums).
//
// What each perturbation draws, besides each point's own noise:
//  - the inlier set itself is resampled: the inliers' weights are multiplied by Exp(1) draws,
//    one per image cell (covariance.resample_cell_px) and perturbation (a Bayesian bootstrap by
//    cell). Errors that vary smoothly over the image (depth distortion, calibration, blur,
//    which the points of a region share) and the choice of inliers spread the perturbations
//    as they spread real estimates: on fr1_xyz, motions fitted to the top and bottom halves of
//    the image disagree 1.5-3x more than random halves do; the model alone cannot see that.
//  - the point noise is scaled by the fit's a-posteriori variance factor (with
//    `residual_variance_factor`),
//      s0^2 = sum_k r_k^T (C_prev,k + R C_curr,k R^T)^-1 r_k / (3n - 6),  floored at 1,
//    with r_k = prev_k - T curr_k: how much noisier this pair's points are than modelled,
//    estimated from its own residuals.
// Then, not per point: a capture-time error of each frame's depth, sigma_t, moves all that
// frame's depths together (by dZ/dt sigma_t each): one common error per frame, which no number
// of points averages away. Its effect g_f = d xi / d t_f is found by refitting with the frame's
// depths moved, and sigma_t^2 (g_prev g_prev^T + g_curr g_curr^T) is added.
// C = scale * (sample covariance + timing term); scale is 1 unless configured.
// Latencies common to consecutive frames need the previous pair: the pair stage adds their
// terms (pipeline/latency_covariance.hpp, with depth_latency_response below).
#include <Eigen/Geometry>
#include <cstdint>
#include <span>
#include <vector>

#include "rgbd_odometry/simd/kernels.hpp"
#include "rgbd_odometry/pipeline/pipeline_config.hpp"
#include "rgbd_odometry/core/geometry.hpp"
#include "rgbd_odometry/pipeline/noise_model.hpp"
#include "rgbd_odometry/core/rng.hpp"

namespace rgbdo {

class PerturbationCovariance {
 public:
  // Buffers are sized for `max_points` inliers here, once; larger inputs grow them.
  PerturbationCovariance(const CovarianceConfig& config, int max_points);

  // prev[k] ~ T curr[k] (the inliers and the fitted motion), each point with its noise;
  // cells[k]: the image cell of pair k for the resampling (empty: none); timing_sigma_s: each
  // frame's capture-time error. Returns false when the result is not
  // finite, symmetric and positive definite.
  [[nodiscard]] bool estimate(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                              const std::vector<PointNoise>& prev_noise, const std::vector<PointNoise>& curr_noise,
                              std::span<const std::uint16_t> cells, const Eigen::Isometry3d& T_prev_curr,
                              double timing_sigma_s, Rng& rng, Matrix6d& covariance);
  // The paper's noise for every point, no resampling, no timing term.
  [[nodiscard]] bool estimate(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                              const Eigen::Isometry3d& T_prev_curr, Rng& rng, Matrix6d& covariance);

  // d xi / d delta per unit camera rate: column i is what reading the current frame's depths
  // delta seconds late does to the fitted motion while the camera moves at unit rate i
  // (xi order: m/s, then rad/s). Uses the last estimate's weights: call after estimate().
  Matrix6d depth_latency_response(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr);

  // The N parameter vectors of the last estimate (tests, diagnostics).
  const std::vector<Vector6d>& samples() const { return samples_; }
  const char* kernel_name() const { return kernels_.name; }
  // The last estimate's timing term (tests).
  const Matrix6d& last_timing_covariance() const { return last_timing_; }

  // s0^2 of the fit (>= 1), as described above.
  static double variance_factor(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                                const std::vector<PointNoise>& prev_noise, const std::vector<PointNoise>& curr_noise,
                                const Eigen::Isometry3d& T_prev_curr);

 private:
  void reserve(int points);
  // The steps of estimate(): both clouds centred on their weighted centroids into the
  // structure of arrays (sigmas times noise_scale), each perturbation's cell weights drawn,
  // the batch kernel's sums and a fit per perturbation into samples_.
  struct Centres {
    Eigen::Vector3d prev = Eigen::Vector3d::Zero(), curr = Eigen::Vector3d::Zero();
  };
  Centres centre_clouds(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                        const std::vector<PointNoise>& prev_noise, const std::vector<PointNoise>& curr_noise,
                        double noise_scale);
  void draw_cell_weights(std::span<const std::uint16_t> cells, Rng& rng);
  bool fit_perturbations(const Centres& centres, Rng& rng);
  // d xi / d t of a capture-time error of one frame's depths (moved along their rays).
  Vector6d timing_gradient(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                           const std::vector<PointNoise>& noise, bool of_prev);
  // d xi / d t of moving one frame's depths along their rays at rates_mps[k].
  Vector6d depth_shift_response(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                                std::span<const double> rates_mps, bool of_prev);
  CovarianceConfig config_;
  const simd::KernelSet& kernels_;
  int padded_perturbations_;
  // Structure of arrays of the centred clouds, their sigmas and the normalised weights.
  std::vector<float> sx_, sy_, sz_, dx_, dy_, dz_, ssx_, ssy_, rsx_, rsy_, rsz_, sdx_, sdy_, rdx_, rdy_, rdz_, w_;
  std::vector<double> weights_;  // the fit's weights before normalisation
  std::vector<float> sums_;  // 15 arrays of padded_perturbations_
  std::vector<Vector6d> samples_;
  std::vector<PointNoise> paper_prev_, paper_curr_;
  static constexpr size_t kMaxCells = 1024;  // reserved once; more cells are still handled
  std::vector<std::uint16_t> cell_;
  std::vector<float> cell_weight_;                       // [cell * padded perturbations + p]
  std::vector<double> cell_total_, perturbation_weight_;  // weight per cell; per perturbation
  std::vector<Eigen::Vector3d> moved_;  // one frame's points with their depths moved
  std::vector<double> rates_;           // and the rates they were moved at
  Matrix6d last_timing_ = Matrix6d::Zero();
};

// Finite, symmetric and positive definite: what an estimator may safely invert.
bool is_valid_covariance(const Matrix6d& c);

}  // namespace rgbdo
