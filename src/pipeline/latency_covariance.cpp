#include "rgbd_odometry/pipeline/latency_covariance.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

namespace rgbdo {
namespace {

// The outer product of a true change from a measured one, D ~ N(change, V), in N dimensions:
// D D^T shrunk by (1 - N / D^T V^-1 D), floored at 0. E[D^T V^-1 D] = N + the true change's own
// (whitened) square, so the factor keeps about that share; a change lost in the noise gives
// nothing, one far above it nearly all of D D^T. (D D^T - V would be unbiased but is not a
// covariance: its other directions are negative.)
template <int N>
Eigen::Matrix<double, N, N> shrunk_outer_product(const Eigen::Matrix<double, N, 1>& change,
                                                 const Eigen::Matrix<double, N, N>& noise) {
  const Eigen::LDLT<Eigen::Matrix<double, N, N>> ldlt(noise);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0)) return change * change.transpose();
  const double whitened = change.dot(ldlt.solve(change));
  if (!(whitened > N)) return Eigen::Matrix<double, N, N>::Zero();
  return (1.0 - N / whitened) * change * change.transpose();
}

// L^2 S S^T in the (rx, ry) block (L = off_s): S the change of the image-shift rate, as rates about x and y
// (a point ahead at inverse depth w shifts by -(tx w + ry), -(ty w - rx)), its outer product
// shrunk by the share its noise explains, as the change of rate's is.
Matrix6d image_shift_term(double off_s, double inverse_depth, const Vector6d& change, const Matrix6d& noise) {
  Eigen::Matrix<double, 2, 6> P = Eigen::Matrix<double, 2, 6>::Zero();
  P(0, 1) = -inverse_depth;
  P(0, 3) = 1;
  P(1, 0) = inverse_depth;
  P(1, 4) = 1;
  const Eigen::Vector2d s = P * change;
  const Eigen::Matrix2d n = P * noise * P.transpose();
  Matrix6d c = Matrix6d::Zero();
  c.block<2, 2>(3, 3) = off_s * off_s * shrunk_outer_product<2>(s, n);
  return c;
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
  if (curr.dt_s <= 0 ||
      (sigmas.colour_s <= 0 && sigmas.depth_s <= 0 && sigmas.translation_s <= 0 && !sigmas.image_shift_term()))
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
  Matrix6d c = through_latencies(sigmas, depth_response, shrunk_outer_product<6>(change, change_noise));
  if (sigmas.image_shift_term()) {
    const double R = sigmas.image_shift_retime_s, interpolation = R * (1 - std::min(1.0, std::abs(R) / curr.dt_s));
    const double off = std::sqrt(sigmas.image_shift_off_s * sigmas.image_shift_off_s + interpolation * interpolation / 2);
    c += image_shift_term(off, curr.inverse_depth, change, change_noise);
  }
  if (sigmas.integration_window_s > 0) {
    const Vector6d& earlier = previous && previous->dt_s > 0 ? previous->rate : curr.rate;
    const Matrix6d rates = curr.rate * curr.rate.transpose() + earlier * earlier.transpose();
    c += (curr.dt_s / sigmas.integration_window_s) * through_latencies(sigmas, depth_response, rates);
  }
  return c;
}

}  // namespace rgbdo
