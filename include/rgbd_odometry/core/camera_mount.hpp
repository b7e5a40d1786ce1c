#pragma once
// Where the camera sits on the vehicle (body.*): the camera-to-body extrinsic that the flight
// link turns the motions with and the gyro's latency fit compares rotations by.
#include <Eigen/Geometry>
#include <limits>

#include "rgbd_odometry/core/settings.hpp"

namespace rgbdo {

// Where the camera sits on the vehicle. The body frame is FRD (x forward, y right, z down);
// with all zeros the camera looks forward along body x, its image x along body y (right) and
// its image y along body z (down). The angles rotate the camera from that mount (Z-Y-X:
// yaw about body z, then pitch, then roll), e.g. pitch -90 for a camera looking down.
struct BodyConfig {
  double camera_roll_deg = 0, camera_pitch_deg = 0, camera_yaw_deg = 0;
  double camera_x_m = 0, camera_y_m = 0, camera_z_m = 0;  // camera position in the body frame
};

// The keys body.* into `table`, pointing into c.
inline void add_body_settings(BodyConfig& c, SettingsTable& table) {
  table.insert(table.end(), {
      {"body.camera_roll_deg", "deg", "camera mount roll from forward-looking (Z-Y-X)", &c.camera_roll_deg, -180, 180},
      {"body.camera_pitch_deg", "deg", "camera mount pitch from forward-looking; -90 looks down", &c.camera_pitch_deg, -90, 90},
      {"body.camera_yaw_deg", "deg", "camera mount yaw from forward-looking", &c.camera_yaw_deg, -180, 180},
      {"body.camera_x_m", "m", "camera position in the FRD body frame, forward", &c.camera_x_m, -10, 10},
      {"body.camera_y_m", "m", "camera position, right", &c.camera_y_m, -10, 10},
      {"body.camera_z_m", "m", "camera position, down", &c.camera_z_m, -10, 10},
  });
}

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
