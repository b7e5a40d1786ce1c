#pragma once
// Rigid-motion helpers shared by the stages: the odometry parameter vector
// xi = (tx, ty, tz, rx, ry, rz) with (rx, ry, rz) the rotation vector (axis * angle).
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace rgbdo {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

Eigen::Vector3d rotation_vector(const Eigen::Matrix3d& R);
Eigen::Matrix3d rotation_from_vector(const Eigen::Vector3d& r);

Vector6d xi_from_transform(const Eigen::Isometry3d& T);
Eigen::Isometry3d transform_from_xi(const Vector6d& xi);

// The cross-product matrix: skew(v) * w == v.cross(w).
inline Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d S;
  S << 0, -v.z(), v.y(),  //
      v.z(), 0, -v.x(),   //
      -v.y(), v.x(), 0;
  return S;
}

// Rotation angle of R in radians, in [0, pi].
double rotation_angle(const Eigen::Matrix3d& R);

}  // namespace rgbdo
