#pragma once
// Kernel interface for the perturbation covariance: for every perturbation p of the inlier
// clouds, the weighted sums from which the absolute-orientation fit of perturbation p follows,
//   S_p = sum_k w_pk s'_k,  D_p = sum_k w_pk d'_k,  M_p = sum_k w_pk d'_k s'_k^T,
// with w_pk = w_k * g_p,cell(k): each perturbation also re-weights the inliers by image cell
// (a resampling of the inlier set; g = 1 keeps every perturbation's weights equal),
// where s'_k = s_k + (sigma_sx_k n0, sigma_sy_k n1, 0) + ray_s_k n2 (and d'_k the same with
// n3 n4 n5) and the n are standard normal draws: two independent lateral errors and one along
// a direction that may couple all three coordinates (a depth error moves a point along its
// viewing ray). The Gaussian noise is generated inside the kernel, vectorised:
//  - 8 independent xoshiro128+ streams, lane l serving perturbations p = 8b + l;
//  - Box-Muller with polynomial log, sin and cos using only +, -, *, / and sqrt, so that the
//    scalar reference and the SIMD twins perform the same IEEE operations (files compiled
//    with -ffp-contract=off). x86 twins are bit-exact; the NEON twin replaces / and sqrt by
//    reciprocal estimates with two Newton steps (ARMv7 NEON has neither), within 2e-6.
// Consumption order of the streams: perturbation block b outer, point k inner, six draws
// per (b, k) per lane.
#include <cstdint>

namespace rgbdo::simd {

constexpr int kPerturbationLanes = 8;

struct PerturbationInput {
  int points = 0;
  int perturbations = 0;  // a multiple of kPerturbationLanes
  // Structure of arrays, one entry per inlier pair; s = current-frame (source) points,
  // d = previous-frame (destination) points, both centred; w normalised to sum 1.
  const float *sx, *sy, *sz, *dx, *dy, *dz;
  const float *sigma_sx, *sigma_sy, *ray_sx, *ray_sy, *ray_sz;
  const float *sigma_dx, *sigma_dy, *ray_dx, *ray_dy, *ray_dz;
  const float* w;
  // cell[k]: the image cell of pair k; cell_weight[c * perturbations + p]: g_p,c.
  const std::uint16_t* cell;
  const float* cell_weight;
  std::uint64_t seed = 0;
};

// 15 arrays of `perturbations` floats each: S (x y z), D (x y z), M (row-major 3x3: d_i s_j).
struct PerturbationSums {
  float* s[3];
  float* d[3];
  float* m[9];
};

#define RGBDO_PERTURBATION_SUMS(name) void name(const PerturbationInput& in, const PerturbationSums& out)
RGBDO_PERTURBATION_SUMS(perturbation_sums_scalar);  // simd/scalar/perturb_scalar.cpp, the reference
RGBDO_PERTURBATION_SUMS(perturbation_sums_avx2);    // simd/x86/perturb_avx2.cpp
RGBDO_PERTURBATION_SUMS(perturbation_sums_neon);    // simd/arm/perturb_neon.cpp

// The reference's normal draws, noise[((p * points) + k) * 6 + c] for c = n0..n5, so that
// tests can rebuild each perturbed cloud and fit it independently.
void perturbation_noise_scalar(std::uint64_t seed, int points, int perturbations, float* noise);

}  // namespace rgbdo::simd
