#pragma once
// Kernel interface for RANSAC hypothesis scoring over structure-of-arrays float coordinates:
// for every correspondence k, e_k = |p_k - (R c_k + t)|^2; returns the number with
// e_k < threshold_sq and the truncated cost sum_k min(e_k, threshold_sq) (MSAC).
// Every twin performs the reference's float operations in the same order without FMA, so
// counts and costs are bit-identical across instruction sets.
#include <cstdint>

namespace rgbdo::simd {

struct RigidScoreInput {
  int n = 0;
  const float *px, *py, *pz;  // previous-frame points
  const float *cx, *cy, *cz;  // current-frame points
  float r[9];                 // row-major rotation
  float t[3];
  float threshold_sq;
};

#define RGBDO_SCORE_RIGID(name) void name(const RigidScoreInput& in, int& count, float& cost)
RGBDO_SCORE_RIGID(score_rigid_scalar);  // simd/scalar/score_scalar.cpp, the reference
RGBDO_SCORE_RIGID(score_rigid_avx2);    // simd/x86/score_avx2.cpp
RGBDO_SCORE_RIGID(score_rigid_neon);    // simd/arm/score_neon.cpp

}  // namespace rgbdo::simd
