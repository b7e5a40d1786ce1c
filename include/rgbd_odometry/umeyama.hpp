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

}  // namespace rgbdo
