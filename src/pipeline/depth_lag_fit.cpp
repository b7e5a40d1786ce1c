#include "rgbd_odometry/pipeline/depth_lag_fit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace rgbdo {
namespace {

// Pairs before the scatter is trusted: the gate judges by it, and the standard error needs it.
constexpr std::uint64_t kLeastPairs = 10;
// chi-square(3)'s 99.9 % point: a pair's whitened residual beyond it is a failed fit's.
constexpr double kGate = 16.27;

}  // namespace

double DepthLagFit::scatter() const {
  if (pairs_ < 1) return std::numeric_limits<double>::infinity();
  const double fitted = sum_gg_ > 0 ? sum_gy_ * sum_gy_ / sum_gg_ : 0.0;
  const double dof = 3.0 * static_cast<double>(pairs_) - 1.0;
  return std::max(0.0, sum_yy_ - fitted) / dof;
}

double DepthLagFit::gate_scatter() const {
  // The scatter of the pairs let in, bounded from below by the median of the last pairs judged,
  // all of them: a gate judging by the first calm pairs' scatter alone would turn away every
  // later pair of a noisier stretch and never learn it (capture_latency.cpp's gate, alike).
  const double s = scatter();
  return judged_.count() >= kLeastPairs ? std::max(s, judged_.median() / kChi2_3_Median) : s;
}

void DepthLagFit::add(const Eigen::Vector3d& y, const Eigen::Vector3d& g) {
  if (!y.allFinite() || !g.allFinite()) return;
  if (pairs_ >= kLeastPairs) {
    const double r2 = (y - lag_s() * g).squaredNorm();
    judged_.push(r2);
    const double s = gate_scatter();
    if (s > 0 && r2 / s > kGate) {
      ++rejected_;
      return;
    }
  }
  sum_gg_ += g.squaredNorm();
  sum_gy_ += g.dot(y);
  sum_yy_ += y.squaredNorm();
  ++pairs_;
}

bool DepthLagFit::known() const { return pairs_ >= kLeastPairs && sum_gg_ > 0; }

double DepthLagFit::sigma_s() const {
  if (!known()) return std::numeric_limits<double>::infinity();
  return std::sqrt(scatter() / sum_gg_);
}

}  // namespace rgbdo
