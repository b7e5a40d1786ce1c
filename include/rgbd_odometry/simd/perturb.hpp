#pragma once
// Kernel interface for the perturbation covariance: for every perturbation p of the inlier
// clouds, the weighted sums from which the absolute-orientation fit of perturbation p follows,
//   S_p = sum_k w_k s'_k,  D_p = sum_k w_k d'_k,  M_p = sum_k w_k d'_k s'_k^T,
// where s'_k = s_k + sigma_s_k * (n0 n1 n2), d'_k = d_k + sigma_d_k * (n3 n4 n5) and the n are
// standard normal draws. The Gaussian noise is generated inside the kernel, vectorised:
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
  const float *sigma_sx, *sigma_sy, *sigma_sz, *sigma_dx, *sigma_dy, *sigma_dz;
  const float* w;
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
