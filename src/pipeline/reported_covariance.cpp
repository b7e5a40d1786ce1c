#include "rgbd_odometry/pipeline/reported_covariance.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>

#include "rgbd_odometry/core/cost_stage.hpp"

namespace rgbdo {
namespace {

// The matrix logarithm of a symmetric positive definite matrix, through its eigenvalues.
Matrix6d symmetric_log(const Eigen::SelfAdjointEigenSolver<Matrix6d>& s) {
  return s.eigenvectors() * s.eigenvalues().array().log().matrix().asDiagonal() * s.eigenvectors().transpose();
}

// root * root^T is the smoothed covariance (root_inv its inverse). In its whitened
// coordinates, a direction where the pair's own is lambda times as wide goes out lambda^2 / r
// as wide, between 1 (the mean, up to sqrt(r)) and lambda (its own, from r): continuous, so
// that no pair's covariance jumps for a small change.
Matrix6d passing_wider(const Matrix6d& own, const Matrix6d& root, const Matrix6d& root_inv, double r) {
  const Eigen::SelfAdjointEigenSolver<Matrix6d> whitened(root_inv * own * root_inv.transpose());
  const Vector6d lambda = whitened.eigenvalues();
  const Vector6d out = lambda.cwiseProduct(lambda / r).cwiseMax(1.0).cwiseMin(lambda.cwiseMax(1.0));
  const Matrix6d m = root * whitened.eigenvectors() * out.asDiagonal() * whitened.eigenvectors().transpose() * root.transpose();
  return 0.5 * (m + m.transpose());
}

}  // namespace

void ReportedCovariance::report(PairResult& pair) {
  if (pair.status == Status::SensorLost) started_ = false;
  if (smoothing_s_ <= 0 || pair.status != Status::Ok || !pair.covariance.allFinite()) return;
  const double dt_s = static_cast<double>(pair.t_curr_ns - pair.t_prev_ns) * 1e-9;
  if (!(dt_s > 0)) return;
  const CostStagesEnd stages_end;
  mark_cost_stage(CostStage::Covariance);
  const Eigen::SelfAdjointEigenSolver<Matrix6d> own(pair.covariance / (dt_s * dt_s));
  if (own.info() != Eigen::Success || !(own.eigenvalues().minCoeff() > 0)) return;
  const Matrix6d log_rate = symmetric_log(own);
  // An exponential mean over time: each pair weighs by the time it covers.
  const double weight = started_ ? 1.0 - std::exp(-dt_s / smoothing_s_) : 1.0;
  mean_log_ += weight * (log_rate - mean_log_);
  started_ = true;
  // One decomposition of the mean gives what goes out (its exponential, at this pair's dt) and
  // the square roots the pass whitens with.
  const Eigen::SelfAdjointEigenSolver<Matrix6d> mean(mean_log_);
  const Matrix6d& axes = mean.eigenvectors();
  const Vector6d sigma = (0.5 * mean.eigenvalues()).array().exp().matrix() * dt_s;
  const Matrix6d root = axes * sigma.asDiagonal();
  if (pass_ratio_ > 0) {
    pair.covariance = passing_wider(pair.covariance, root, sigma.cwiseInverse().asDiagonal() * axes.transpose(), pass_ratio_);
  } else {
    const Matrix6d smoothed = root * root.transpose();
    pair.covariance = 0.5 * (smoothed + smoothed.transpose());
  }
}

}  // namespace rgbdo
