#pragma once
// Where the camera sits on the vehicle (body.*, config.hpp): the camera-to-body extrinsic that
// the flight link turns the motions with and the gyro's latency fit compares rotations by.
#include <Eigen/Geometry>

#include "rgbd_odometry/core/config.hpp"

namespace rgbdo {

struct CameraExtrinsic {
  Eigen::Matrix3d R_body_camera = forward_looking_rotation();  // camera axes in body axes
  Eigen::Vector3d p_body_camera_m = Eigen::Vector3d::Zero();    // camera position in body frame

  // All of body.* zero: the camera looks along body x, its image x along body y, image y along body z.
  static Eigen::Matrix3d forward_looking_rotation() {
    Eigen::Matrix3d R;
    R << 0, 0, 1,  //
        1, 0, 0,   //
        0, 1, 0;
    return R;
  }
};

// The extrinsic of body.*: R_body_camera = Rz(yaw) Ry(pitch) Rx(roll) forward_looking_rotation().
CameraExtrinsic extrinsic_from(const BodyConfig& body);

// (roll, pitch, yaw) of R = Rz(yaw) Ry(pitch) Rx(roll), radians.
Eigen::Vector3d euler_zyx(const Eigen::Matrix3d& R);

}  // namespace rgbdo
