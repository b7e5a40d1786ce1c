#pragma once
// Rigid-motion helpers shared by the stages: the odometry parameter vector
// xi = (tx, ty, tz, rx, ry, rz) with (rx, ry, rz) the rotation vector (axis * angle).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

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

// The unbiased sample covariance of parameter vectors (at least two).
Matrix6d sample_covariance(const std::vector<Vector6d>& samples);

// Rotation angle of R in radians, in [0, pi].
double rotation_angle(const Eigen::Matrix3d& R);

// First-order uncertainty of composed motions uses right perturbations of SE(3):
// T_true = T * Exp(delta), delta = (rho, phi), translation first. Composing A * T * B turns a
// perturbation delta of T into Ad(B^-1) * delta of the product.
Matrix6d se3_adjoint(const Eigen::Isometry3d& T);  // [[R, skew(t) R], [0, R]]

// The right Jacobian of SO(3): exp(r + dr) ~ exp(r) * exp(J_r(r) dr).
Eigen::Matrix3d so3_right_jacobian(const Eigen::Vector3d& r);

// A covariance of xi = (t, rotation vector) of T, expressed as a right perturbation of T
// (rho = R^T dt, phi = J_r(r) dr).
Matrix6d right_perturbation_covariance(const Eigen::Isometry3d& T, const Matrix6d& xi_covariance);
// Its inverse: the covariance of xi from that of the right perturbation of T.
Matrix6d xi_covariance_from_right_perturbation(const Eigen::Isometry3d& T, const Matrix6d& perturbation_covariance);

// The right perturbation taking `reference` to `estimate`: (R_ref^T (t_est - t_ref), Log(R_ref^T R_est)).
Vector6d right_perturbation_between(const Eigen::Isometry3d& reference, const Eigen::Isometry3d& estimate);

}  // namespace rgbdo
