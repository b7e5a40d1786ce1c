#include "rgbd_odometry/core/geometry.hpp"

#include <Eigen/LU>
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

Matrix6d sample_covariance(const std::vector<Vector6d>& samples) {
  Vector6d mean = Vector6d::Zero();
  for (const auto& x : samples) mean += x;
  mean /= static_cast<double>(samples.size());
  Matrix6d c = Matrix6d::Zero();
  for (const auto& x : samples) c += (x - mean) * (x - mean).transpose();
  return c / static_cast<double>(samples.size() - 1);
}

double rotation_angle(const Eigen::Matrix3d& R) {
  // acos of the trace loses precision near 0, where frame-to-frame rotations live.
  return Eigen::AngleAxisd(R).angle();
}

Matrix6d se3_adjoint(const Eigen::Isometry3d& T) {
  Matrix6d ad = Matrix6d::Zero();
  const Eigen::Matrix3d R = T.linear();
  ad.topLeftCorner<3, 3>() = R;
  ad.topRightCorner<3, 3>() = skew(T.translation()) * R;
  ad.bottomRightCorner<3, 3>() = R;
  return ad;
}

Eigen::Matrix3d so3_right_jacobian(const Eigen::Vector3d& r) {
  const double angle = r.norm();
  const Eigen::Matrix3d K = skew(r);
  // Below ~1e-4 rad the closed form loses digits to cancellation; its series is exact there
  // to double precision after three terms.
  if (angle < 1e-4) return Eigen::Matrix3d::Identity() - 0.5 * K + (1.0 / 6.0) * K * K;
  const double a2 = angle * angle;
  return Eigen::Matrix3d::Identity() - (1 - std::cos(angle)) / a2 * K + (angle - std::sin(angle)) / (a2 * angle) * K * K;
}

Matrix6d right_perturbation_covariance(const Eigen::Isometry3d& T, const Matrix6d& xi_covariance) {
  Matrix6d J = Matrix6d::Zero();
  J.topLeftCorner<3, 3>() = T.linear().transpose();
  J.bottomRightCorner<3, 3>() = so3_right_jacobian(rotation_vector(T.linear()));
  return J * xi_covariance * J.transpose();
}

Matrix6d xi_covariance_from_right_perturbation(const Eigen::Isometry3d& T, const Matrix6d& perturbation_covariance) {
  Matrix6d J = Matrix6d::Zero();
  J.topLeftCorner<3, 3>() = T.linear();
  J.bottomRightCorner<3, 3>() = so3_right_jacobian(rotation_vector(T.linear())).inverse();
  return J * perturbation_covariance * J.transpose();
}

Vector6d right_perturbation_between(const Eigen::Isometry3d& reference, const Eigen::Isometry3d& estimate) {
  Vector6d d;
  d.head<3>() = reference.linear().transpose() * (estimate.translation() - reference.translation());
  d.tail<3>() = rotation_vector(reference.linear().transpose() * estimate.linear());
  return d;
}

}  // namespace rgbdo
