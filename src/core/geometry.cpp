#include "rgbd_odometry/core/geometry.hpp"

#include <cmath>

namespace rgbdo {

Eigen::Vector3d rotation_vector(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.axis() * aa.angle();
}

Eigen::Matrix3d rotation_from_vector(const Eigen::Vector3d& r) {
  const double angle = r.norm();
  if (angle < 1e-15) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, r / angle).toRotationMatrix();
}

Vector6d xi_from_transform(const Eigen::Isometry3d& T) {
  Vector6d xi;
  xi.head<3>() = T.translation();
  xi.tail<3>() = rotation_vector(T.linear());
  return xi;
}

Eigen::Isometry3d transform_from_xi(const Vector6d& xi) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = rotation_from_vector(xi.tail<3>());
  T.translation() = xi.head<3>();
  return T;
}

double rotation_angle(const Eigen::Matrix3d& R) {
  // acos of the trace loses precision near 0, where frame-to-frame rotations live.
  return Eigen::AngleAxisd(R).angle();
}

}  // namespace rgbdo
