#pragma once
// Stage 5: the odometry covariance by statistical perturbation (Willis & Brink Sec. III-C).
// The inlier point pairs are perturbed N times with the sensor noise model, each perturbed
// pair of clouds is aligned again, and the unbiased sample covariance of the N parameter
// vectors xi = (t, rotation vector) is the estimate, multiplied by the configured scale.
//
// All N perturbations are generated and accumulated together by the active SIMD kernel
// (rgbd_odometry/simd/perturb.hpp: vectorised Gaussian noise, structure-of-arrays weighted sums of the
// centred clouds), then each perturbation's motion follows from its sums by one fixed-size
// 3x3 solve (fit_from_sums). The fit is the estimate's own weighted least squares.
//
// The noise model is a lower bound: real keypoints are off by more than it predicts
// (localisation, depth quantisation, registration). With `residual_variance_factor` the
// sample covariance is also multiplied by the a-posteriori variance factor of the fit,
//   s0^2 = sum_k w_k |prev_k - T curr_k|^2 / (n - 2),  floored at 1,
// the least-squares estimate of how much noisier this pair's points are than modelled:
// a pair with sloppy inliers then reports a proportionally larger covariance.
#include <Eigen/Geometry>
#include <vector>

#include "rgbd_odometry/simd/kernels.hpp"
#include "rgbd_odometry/core/config.hpp"
#include "rgbd_odometry/core/geometry.hpp"
#include "rgbd_odometry/core/rng.hpp"

namespace rgbdo {

class PerturbationCovariance {
 public:
  // Buffers are sized for `max_points` inliers here, once; larger inputs grow them.
  PerturbationCovariance(const CovarianceConfig& config, int max_points);

  // prev[k] ~ T curr[k] (the inliers and the fitted motion); returns false when the result
  // is not finite, symmetric and positive definite.
  [[nodiscard]] bool estimate(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                              const Eigen::Isometry3d& T_prev_curr, Rng& rng, Matrix6d& covariance);

  // The N parameter vectors of the last estimate (tests, diagnostics).
  const std::vector<Vector6d>& samples() const { return samples_; }
  const char* kernel_name() const { return kernels_.name; }

  // s0^2 of the fit (>= 1), as described above.
  static double variance_factor(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                                const Eigen::Isometry3d& T_prev_curr, double depth_noise_coeff);

 private:
  void reserve(int points);
  CovarianceConfig config_;
  const simd::KernelSet& kernels_;
  int padded_perturbations_;
  // Structure of arrays of the centred clouds, their sigmas and the normalised weights.
  std::vector<float> sx_, sy_, sz_, dx_, dy_, dz_, ssx_, ssy_, ssz_, sdx_, sdy_, sdz_, w_;
  std::vector<double> weights_;  // the fit's weights before normalisation
  std::vector<float> sums_;  // 15 arrays of padded_perturbations_
  std::vector<Vector6d> samples_;
};

// Finite, symmetric and positive definite: what an estimator may safely invert.
bool is_valid_covariance(const Matrix6d& c);

}  // namespace rgbdo
