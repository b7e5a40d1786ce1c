#include "rgbd_odometry/umeyama.hpp"

#include <Eigen/SVD>

namespace rgbdo {

bool fit_rigid(std::span<const Eigen::Vector3d> src, std::span<const Eigen::Vector3d> dst,
               std::span<const double> weights, Eigen::Isometry3d& T_dst_src) {
  const size_t n = src.size();
  if (n < 3 || dst.size() != n || (!weights.empty() && weights.size() != n)) return false;
  const auto w = [&](size_t k) { return weights.empty() ? 1.0 : weights[k]; };

  double total = 0;
  Eigen::Vector3d mean_src = Eigen::Vector3d::Zero(), mean_dst = Eigen::Vector3d::Zero();
  for (size_t k = 0; k < n; ++k) {
    total += w(k);
    mean_src += w(k) * src[k];
    mean_dst += w(k) * dst[k];
  }
  if (!(total > 0)) return false;
  mean_src /= total;
  mean_dst /= total;

  Eigen::Matrix3d cross = Eigen::Matrix3d::Zero();  // sum w (dst - mean)(src - mean)^T
  for (size_t k = 0; k < n; ++k) cross += w(k) * (dst[k] - mean_dst) * (src[k] - mean_src).transpose();
  // Centred first (better conditioned than raw sums), then the shared solve.
  if (!fit_from_sums(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), cross, total, T_dst_src)) return false;
  T_dst_src.translation() = mean_dst - T_dst_src.linear() * mean_src;
  return true;
}

bool fit_from_sums(const Eigen::Vector3d& sum_s, const Eigen::Vector3d& sum_d, const Eigen::Matrix3d& sum_ds,
                   double total, Eigen::Isometry3d& T_dst_src) {
  if (!(total > 0)) return false;
  const Eigen::Vector3d mean_src = sum_s / total, mean_dst = sum_d / total;
  const Eigen::Matrix3d cross = sum_ds - total * mean_dst * mean_src.transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cross, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Vector3d s = svd.singularValues();
  // Rank < 2 (coincident or collinear points): the rotation about their line is free.
  if (!(s(0) > 0) || s(1) <= 1e-12 * s(0)) return false;
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) D(2, 2) = -1;  // no reflections
  const Eigen::Matrix3d R = svd.matrixU() * D * svd.matrixV().transpose();

  T_dst_src = Eigen::Isometry3d::Identity();
  T_dst_src.linear() = R;
  T_dst_src.translation() = mean_dst - R * mean_src;
  return true;
}

}  // namespace rgbdo
