#pragma once
// Absolute orientation (Umeyama 1991; Horn 1987): the rigid T minimising
// sum_k w_k |dst_k - T src_k|^2, reflections excluded.
#include <Eigen/Geometry>
#include <span>

namespace rgbdo {

// Returns false when the points do not fix a rotation (fewer than 3, or collinear).
// weights: empty for unit weights, else one non-negative weight per pair.
[[nodiscard]] bool fit_rigid(std::span<const Eigen::Vector3d> src, std::span<const Eigen::Vector3d> dst,
                             std::span<const double> weights, Eigen::Isometry3d& T_dst_src);

// The same least-squares fit for exactly three pairs, without an SVD: three points are
// coplanar, so the optimal rotation turns the source triangle's normal onto the
// destination's and then solves the 2-D Procrustes angle in that plane in closed form.
// (Equal to fit_rigid up to rounding whenever the two triangles have the same orientation,
// as they do for a true correspondence under a rotation; a mirrored pair, which no rotation
// explains, is fitted with its normals aligned.) False for degenerate triangles.
[[nodiscard]] bool fit_triplet(const Eigen::Vector3d src[3], const Eigen::Vector3d dst[3], Eigen::Isometry3d& T_dst_src);

// The same fit from the weighted sums alone, sum_s = sum w s, sum_d = sum w d,
// sum_ds = sum w d s^T, total = sum w: the small fixed-size solve (3x3 SVD, reflections
// excluded) that the batched covariance runs once per perturbation.
[[nodiscard]] bool fit_from_sums(const Eigen::Vector3d& sum_s, const Eigen::Vector3d& sum_d, const Eigen::Matrix3d& sum_ds,
                                 double total, Eigen::Isometry3d& T_dst_src);

}  // namespace rgbdo
