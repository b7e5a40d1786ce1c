#pragma once
// Stage 6: the trajectory, by chaining frame-to-frame motions. A failed pair contributes
// the identity (the odometry log's convention): the integrator never invents motion.
#include <Eigen/Geometry>
#include <cstdint>

namespace rgbdo {

class TrajectoryIntegrator {
 public:
  explicit TrajectoryIntegrator(const Eigen::Isometry3d& origin = Eigen::Isometry3d::Identity()) : pose_(origin) {}
  // T_prev_curr: pose of the current camera in the previous camera's frame.
  void add(const Eigen::Isometry3d& T_prev_curr) {
    pose_ = pose_ * T_prev_curr;
    // Re-orthonormalise: thousands of products drift off SO(3) in floating point.
    pose_.linear() = Eigen::Quaterniond(pose_.linear()).normalized().toRotationMatrix();
  }
  const Eigen::Isometry3d& pose() const { return pose_; }  // current camera in the origin's frame

 private:
  Eigen::Isometry3d pose_;
};

}  // namespace rgbdo
