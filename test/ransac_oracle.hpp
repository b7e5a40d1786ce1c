#pragma once
// An oracle for RigidRansac built from what it promises, not from how it is written: none of
// ransac.cpp's or umeyama.cpp's code. Its own weighted Kabsch fit (Eigen's SVD), the paper's
// refinement rule and a numerical test of the final fit's optimality.
//
// What a result must satisfy (Willis & Brink, PCL's refineModel, and the final fit):
//  1. the refinement's fixed point: the inliers are exactly the pairs within the threshold
//     of the least-squares motion fitted to those inliers, with the threshold
//     min(3 sigma, lambda), sigma the RMS residual of that fit;
//  2. the final motion is a local minimum of the Mahalanobis cost
//     sum_k r_k^T (C_prev + R C_curr R^T)^-1 r_k over the inliers (the covariances frozen at
//     the motion, as a Gauss-Newton step sees them), unless the refinement was refused as a
//     jump larger than lambda, in which case it is the least-squares motion itself.
#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <vector>

#include "rgbd_odometry/pipeline/noise_model.hpp"

namespace rgbdo::oracle {

// Weighted least squares: the motion T minimising sum w_k |prev_k - T curr_k|^2 (Kabsch with
// weights, the reflection case excluded).
inline Eigen::Isometry3d weighted_kabsch(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                                         const std::vector<int>& pairs, const std::vector<double>& weights) {
  double total = 0;
  Eigen::Vector3d mean_p = Eigen::Vector3d::Zero(), mean_c = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < pairs.size(); ++i) {
    total += weights[i];
    mean_p += weights[i] * prev[static_cast<size_t>(pairs[i])];
    mean_c += weights[i] * curr[static_cast<size_t>(pairs[i])];
  }
  mean_p /= total;
  mean_c /= total;
  Eigen::Matrix3d cross = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < pairs.size(); ++i)
    cross += weights[i] * (prev[static_cast<size_t>(pairs[i])] - mean_p) * (curr[static_cast<size_t>(pairs[i])] - mean_c).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cross, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1 : 1;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = svd.matrixU() * D * svd.matrixV().transpose();
  T.translation() = mean_p - T.linear() * mean_c;
  return T;
}

// The paper model's weight of a pair: the inverse of its total variance.
inline double paper_weight(const Eigen::Vector3d& prev, const Eigen::Vector3d& curr, double depth_noise_coeff) {
  const auto variance = [&](const Eigen::Vector3d& p) {
    const double sz = depth_noise_coeff * p.z() * p.z();
    return sz * sz * (1 + (p.x() * p.x() + p.y() * p.y()) / (p.z() * p.z()));
  };
  return 1.0 / (variance(prev) + variance(curr));
}

struct FixedPoint {
  Eigen::Isometry3d least_squares;  // fitted to the result's inliers
  double threshold_m = 0;           // min(3 sigma, lambda) of that fit
  std::vector<int> inliers;         // the pairs within the threshold of that fit
};

inline FixedPoint refinement_fixed_point(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                                         const std::vector<int>& inliers, double lambda_m, double depth_noise_coeff) {
  FixedPoint f;
  std::vector<double> w;
  for (int k : inliers) w.push_back(paper_weight(prev[static_cast<size_t>(k)], curr[static_cast<size_t>(k)], depth_noise_coeff));
  f.least_squares = weighted_kabsch(prev, curr, inliers, w);
  double sum_sq = 0;
  for (int k : inliers) sum_sq += (prev[static_cast<size_t>(k)] - f.least_squares * curr[static_cast<size_t>(k)]).squaredNorm();
  f.threshold_m = std::min(3 * std::sqrt(sum_sq / static_cast<double>(inliers.size())), lambda_m);
  for (size_t k = 0; k < prev.size(); ++k)
    if ((prev[k] - f.least_squares * curr[k]).norm() < f.threshold_m) f.inliers.push_back(static_cast<int>(k));
  return f;
}

// The Mahalanobis cost of motion `T`, the point covariances rotated by `frozen`'s rotation.
inline double mahalanobis_cost(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                               const std::vector<int>& inliers, const SensorNoise& noise, const Eigen::Isometry3d& T,
                               const Eigen::Isometry3d& frozen) {
  double cost = 0;
  for (int k : inliers) {
    const Eigen::Vector3d& p = prev[static_cast<size_t>(k)];
    const Eigen::Vector3d& c = curr[static_cast<size_t>(k)];
    const Eigen::Matrix3d C = point_covariance(p, noise) + frozen.linear() * point_covariance(c, noise) * frozen.linear().transpose();
    const Eigen::Vector3d r = p - T * c;
    cost += r.dot(C.ldlt().solve(r));
  }
  return cost;
}

// Whether no step of h (metres, radians) along any axis of translation or rotation lowers
// the cost by more than `slack` of it.
inline bool is_local_minimum(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                             const std::vector<int>& inliers, const SensorNoise& noise, const Eigen::Isometry3d& T,
                             double h, double slack) {
  const double at = mahalanobis_cost(prev, curr, inliers, noise, T, T);
  for (int axis = 0; axis < 6; ++axis)
    for (double sign : {-1.0, 1.0}) {
      Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
      if (axis < 3) step.translation()(axis) = sign * h;
      else step.linear() = Eigen::AngleAxisd(sign * h, Eigen::Vector3d::Unit(axis - 3)).toRotationMatrix();
      if (mahalanobis_cost(prev, curr, inliers, noise, step * T, T) < at * (1 - slack)) return false;
    }
  return true;
}

}  // namespace rgbdo::oracle
