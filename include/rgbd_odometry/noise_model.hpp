#pragma once
// The depth sensor's measurement noise (Willis & Brink eq. 2, after Khoshelham & Elberink):
//   sigma_Z = c Z^2,  sigma_X = |X/Z| sigma_Z,  sigma_Y = |Y/Z| sigma_Z,  c = 1.425e-3 / m.
// Used to perturb points for the covariance and to weight the final least-squares fit.
#include <Eigen/Core>
#include <cmath>

namespace rgbdo {

inline Eigen::Vector3d point_sigma(const Eigen::Vector3d& p, double depth_noise_coeff) {
  const double sz = depth_noise_coeff * p.z() * p.z();
  return {std::abs(p.x() / p.z()) * sz, std::abs(p.y() / p.z()) * sz, sz};
}

// Weight of a correspondence in the final fit: inverse of its total expected variance.
inline double pair_weight(const Eigen::Vector3d& prev, const Eigen::Vector3d& curr, double depth_noise_coeff) {
  return 1.0 / (point_sigma(prev, depth_noise_coeff).squaredNorm() + point_sigma(curr, depth_noise_coeff).squaredNorm());
}

}  // namespace rgbdo
