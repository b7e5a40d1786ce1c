#include "rgbd_odometry/pipeline/latency_covariance.hpp"

#include <Eigen/Cholesky>

namespace rgbdo {
namespace {

// The outer product of the true change of rate, from a measured change D ~ N(change, V): D D^T
// shrunk by (1 - 6 / D^T V^-1 D), floored at 0. E[D^T V^-1 D] = 6 + the true change's own
// (whitened) square, so the factor keeps about that share; a change lost in the noise gives
// nothing, one far above it nearly all of D D^T. (D D^T - V would be unbiased but is not a
// covariance: its other five directions are negative.)
Matrix6d change_outer_product(const Vector6d& change, const Matrix6d& noise) {
  const Eigen::LDLT<Matrix6d> ldlt(noise);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0)) return change * change.transpose();
  const double whitened = change.dot(ldlt.solve(change));
  if (!(whitened > 6.0)) return Matrix6d::Zero();
  return (1.0 - 6.0 / whitened) * change * change.transpose();
}

// sigma_c^2 M + sigma_d^2 G M G^T + sigma_t^2 M_tt: one outer product of rates through the latencies.
Matrix6d through_latencies(const LatencySigmas& s, const Matrix6d& depth_response, const Matrix6d& m) {
  Matrix6d c = s.colour_s * s.colour_s * m + s.depth_s * s.depth_s * depth_response * m * depth_response.transpose();
  c.topLeftCorner<3, 3>() += s.translation_s * s.translation_s * m.topLeftCorner<3, 3>();
  return c;
}

}  // namespace

Matrix6d latency_covariance(const LatencySigmas& sigmas, const Matrix6d& depth_response, const PairRate& curr,
                            const std::optional<PairRate>& previous) {
  if (curr.dt_s <= 0 || (sigmas.colour_s <= 0 && sigmas.depth_s <= 0 && sigmas.translation_s <= 0))
    return Matrix6d::Zero();
  // The change of rate between the pair's two frames, from the two pairs' mean rates (whose
  // midpoints are (dt + dt') / 2 apart), and how much of its outer product is their noise.
  Vector6d change = curr.rate;
  Matrix6d change_noise = curr.covariance / (curr.dt_s * curr.dt_s);
  if (previous && previous->dt_s > 0) {
    const double stretch = 2 * curr.dt_s / (curr.dt_s + previous->dt_s);
    change = stretch * (curr.rate - previous->rate);
    change_noise = stretch * stretch * (change_noise + previous->covariance / (previous->dt_s * previous->dt_s));
  }
  Matrix6d c = through_latencies(sigmas, depth_response, change_outer_product(change, change_noise));
  if (sigmas.integration_window_s > 0) {
    const Vector6d& earlier = previous && previous->dt_s > 0 ? previous->rate : curr.rate;
    const Matrix6d rates = curr.rate * curr.rate.transpose() + earlier * earlier.transpose();
    c += (curr.dt_s / sigmas.integration_window_s) * through_latencies(sigmas, depth_response, rates);
  }
  return c;
}

}  // namespace rgbdo
