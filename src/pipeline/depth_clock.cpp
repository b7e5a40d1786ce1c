#include "rgbd_odometry/pipeline/depth_clock.hpp"

namespace rgbdo {

Eigen::Isometry3d at_colour_instants(const Eigen::Isometry3d& measured, double shift_a_m, double shift_b_m) {
  if (shift_a_m == 0 && shift_b_m == 0) return measured;
  Eigen::Isometry3d out = measured;
  // Tz(-s_a) · M · Tz(s_b): the rotation stays, the translation moves by -s_a z_a + R s_b z_b.
  out.translation() += shift_b_m * measured.linear().col(2) - shift_a_m * Eigen::Vector3d::UnitZ();
  return out;
}

Eigen::Isometry3d DepthClock::carry(const Eigen::Isometry3d& measured, double dt_s, double restamped_s) {
  if (lag_s_ == 0 || !(dt_s > 0)) return measured;
  const double lag_s = lag_s_ - restamped_s;
  velocity_z_[static_cast<size_t>(next_)] = measured.translation().z() / dt_s;
  next_ = (next_ + 1) % kVelocityPairs;
  if (count_ < kVelocityPairs) ++count_;
  double mean = 0;
  for (int i = 0; i < count_; ++i) mean += velocity_z_[static_cast<size_t>(i)];
  mean /= count_;
  const double prev_shift = shift_m_;
  shift_m_ = lag_s * mean;
  // The first pair after a gap: the older frame's velocity is unknown; the pair is left as
  // measured, and the newer frame's shift starts the chain.
  if (count_ == 1) return measured;
  return at_colour_instants(measured, prev_shift, shift_m_);
}

void DepthClock::forget() {
  count_ = 0;
  next_ = 0;
  shift_m_ = 0;
}

}  // namespace rgbdo
