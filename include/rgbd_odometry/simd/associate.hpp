#pragma once
// The depth alignment's association (pipeline/depth_alignment.cpp): one grid row of the
// current frame's points carried into the previous frame by (R, t), projected onto its grid
// and associated point-to-plane, each association's residual, weight and Jacobian written out.
// Every twin performs the reference's float operations in the same order without FMA, and
// divides as IEEE division does (NEON, which has no divide, lane by lane on VFP), so that the
// associations are bit-identical across instruction sets.
#include <cstdint>

namespace rgbdo::simd {

struct AssociateInput {
  const float* curr;  // the row's first point, (x, y, z) interleaved; z = 0: no point
  int n;              // the points taken: curr[3 * step * i], i < n
  int step;           // 1 (every point) or 2 (every other)
  int first_index;    // the grid index of curr[0]; the i-th point taken is first_index + step * i
  const float* prev_point;   // the previous grid's points, (x, y, z) interleaved
  const float* prev_normal;  // and normals; (0, 0, 0): none
  int cols, rows;            // the grid
  float r[9];                // row-major rotation, current frame to previous
  float t[3];
  float fx, fy, cx, cy;  // the grid's intrinsics, cx and cy with + 0.5 (truncation rounds)
  float max_d2;          // an association further apart than this (m^2) is none
  float coeff, floor2;   // depth noise c (sigma_Z = c Z^2) and the rounding variance floor
};

// One association: q = R p + t lands on the previous grid's sample k, d = q - point_k,
// r = n_k . d, w = 1 / ((c Z_p^2)^2 + (c Z_k^2)^2 + floor2), j = (m, a x m) with m = R^T n_k
// and the lever arm a = p - R^T d / 2, the midpoint of the point and its target in the current
// frame. The converged rotation solves sum w (a x m) r = 0; with the lever arm at p alone that
// equation leans on the current frame's noisy point and not on the previous one's, so under
// depth noise a pair and the same pair reversed solve different equations and their biases add
// up there and back instead of cancelling. At the midpoint both frames weigh alike.
struct Association {
  float r, w;
  float j[6];
  std::int32_t curr_index, prev_index;
};

// Writes the row's associations in the order of its points; returns how many.
// `out` has room for n.
#define RGBDO_ASSOCIATE(name) int name(const AssociateInput& in, Association* out)
RGBDO_ASSOCIATE(associate_scalar);  // simd/scalar/associate_scalar.cpp, the reference
RGBDO_ASSOCIATE(associate_avx2);    // simd/x86/associate_avx2.cpp
RGBDO_ASSOCIATE(associate_neon);    // simd/arm/associate_neon.cpp

}  // namespace rgbdo::simd
