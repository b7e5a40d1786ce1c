#include "rgbd_odometry/core/umeyama.hpp"

#include <Eigen/SVD>
#include <cmath>

#include "rgbd_odometry/core/geometry.hpp"

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

bool fit_triplet(const Eigen::Vector3d src[3], const Eigen::Vector3d dst[3], Eigen::Isometry3d& T_dst_src) {
  const Eigen::Vector3d cs = (src[0] + src[1] + src[2]) / 3.0, cd = (dst[0] + dst[1] + dst[2]) / 3.0;
  Eigen::Vector3d ns = (src[1] - src[0]).cross(src[2] - src[0]);
  Eigen::Vector3d nd = (dst[1] - dst[0]).cross(dst[2] - dst[0]);
  const double ls = ns.norm(), ld = nd.norm();
  if (!(ls > 1e-12) || !(ld > 1e-12)) return false;
  ns /= ls;
  nd /= ld;
  // R1: the shortest rotation taking ns to nd (Rodrigues); half a turn when they oppose.
  Eigen::Matrix3d R1;
  const double c = ns.dot(nd);
  if (c > -1.0 + 1e-12) {
    const Eigen::Vector3d v = ns.cross(nd);
    const Eigen::Matrix3d vx = skew(v);
    R1 = Eigen::Matrix3d::Identity() + vx + vx * vx / (1.0 + c);
  } else {
    const Eigen::Vector3d axis = (src[1] - src[0]).normalized();  // lies in the source plane
    R1 = 2.0 * axis * axis.transpose() - Eigen::Matrix3d::Identity();
  }
  // In the destination plane: the angle about nd that best aligns the rotated source.
  double sin_sum = 0, cos_sum = 0;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d q = R1 * (src[i] - cs), p = dst[i] - cd;
    sin_sum += nd.dot(q.cross(p));
    cos_sum += q.dot(p);
  }
  const double theta = std::atan2(sin_sum, cos_sum);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(theta, nd).toRotationMatrix() * R1;
  T_dst_src = Eigen::Isometry3d::Identity();
  T_dst_src.linear() = R;
  T_dst_src.translation() = cd - R * cs;
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
