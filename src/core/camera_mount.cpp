#include "rgbd_odometry/core/camera_mount.hpp"

#include <algorithm>
#include <cmath>

namespace rgbdo {

CameraExtrinsic extrinsic_from(const BodyConfig& body) {
  constexpr double kDegToRad = M_PI / 180.0;
  CameraExtrinsic x;
  const Eigen::Matrix3d mount = (Eigen::AngleAxisd(body.camera_yaw_deg * kDegToRad, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(body.camera_pitch_deg * kDegToRad, Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(body.camera_roll_deg * kDegToRad, Eigen::Vector3d::UnitX()))
                                    .toRotationMatrix();
  x.R_body_camera = mount * CameraExtrinsic::forward_looking_rotation();
  x.p_body_camera_m = Eigen::Vector3d(body.camera_x_m, body.camera_y_m, body.camera_z_m);
  return x;
}

Eigen::Vector3d euler_zyx(const Eigen::Matrix3d& R) {
  return {std::atan2(R(2, 1), R(2, 2)), std::asin(std::clamp(-R(2, 0), -1.0, 1.0)), std::atan2(R(1, 0), R(0, 0))};
}

}  // namespace rgbdo
