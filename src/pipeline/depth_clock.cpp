#include "rgbd_odometry/pipeline/depth_clock.hpp"

#include "rgbd_odometry/core/geometry.hpp"

namespace rgbdo {

Eigen::Isometry3d at_colour_instants(const Eigen::Isometry3d& measured, const Eigen::Isometry3d& shift_a,
                                     const Eigen::Isometry3d& shift_b) {
  return shift_a.inverse() * measured * shift_b;
}

Eigen::Isometry3d DepthClock::carry(const Eigen::Isometry3d& measured, double dt_s, double restamped_s,
                                    bool rotations_timed, double inverse_depth, double image_shift_retime_s) {
  if (!(inverse_depth > 0)) image_shift_retime_s = 0;
  // Nothing to carry, and nothing carried into the older frame: the motion as measured.
  if ((lag_s_ == 0 && tilt_lag_s_ == 0 && image_shift_retime_s == 0 && count_ == 0) || !(dt_s > 0)) return measured;
  const double lag_s = lag_s_ == 0 ? 0.0 : lag_s_ - restamped_s;
  // Where a gyro times the rotations (capture_latency.hpp), their instants are its business: the
  // pairs are restamped at them once it has converged, and until then the latency priors cover
  // them. Carried as well, a tilt would be moved twice.
  const double tilt_lag_s = rotations_timed || !(inverse_depth > 0) ? 0.0 : tilt_lag_s_;
  const Eigen::Vector3d rotation = rotation_vector(measured.linear());
  rates_[static_cast<size_t>(next_)] = Eigen::Vector3d(measured.translation().z(), rotation.x(), rotation.y()) / dt_s;
  next_ = (next_ + 1) % kVelocityPairs;
  if (count_ < kVelocityPairs) ++count_;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int i = 0; i < count_; ++i) mean += rates_[static_cast<size_t>(i)];
  mean /= count_;
  const Eigen::Isometry3d prev_shift = shift_;
  shift_.setIdentity();
  const Eigen::Vector3d tilt(tilt_lag_s * mean(1), tilt_lag_s * mean(2), 0);
  shift_.linear() = rotation_from_vector(tilt);
  // The image shift of a point ahead at the inliers' mean depth (tx w + ry, ty w - rx) is the
  // colour's own and on its stamps: the tilt is carried along the slide, the sideways
  // translation taking the opposite share.
  const double depth = tilt_lag_s != 0 ? 1.0 / inverse_depth : 0.0;
  shift_.translation() = Eigen::Vector3d(-depth * tilt.y(), depth * tilt.x(), lag_s * mean(0));
  if (image_shift_retime_s != 0) {
    // Back R / dt of this pair's image shift (tx w + ry, ty w - rx), as a translation.
    const double back = image_shift_retime_s / dt_s;
    const Eigen::Vector3d& t = measured.translation();
    shift_.translation().x() -= back * (t.x() + rotation.y() / inverse_depth);
    shift_.translation().y() -= back * (t.y() - rotation.x() / inverse_depth);
  }
  // The first pair after a gap: the older frame's rate is unknown; the pair is left as
  // measured, and the newer frame's shift starts the chain.
  if (count_ == 1) return measured;
  return at_colour_instants(measured, prev_shift, shift_);
}

void DepthClock::forget() {
  count_ = 0;
  next_ = 0;
  shift_.setIdentity();
}

}  // namespace rgbdo
