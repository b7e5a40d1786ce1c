#pragma once
// Stage 7 (contents): what the flight computer is told, made from the pipeline's pair results.
// The framing is mavlink.hpp; this file decides frames, units, covariances and failure values.
//
// Conventions
// - Camera frame: OpenCV (x right, y down, z forward). PairResult::T_prev_curr is the pose of
//   the current camera in the previous camera's frame; PairResult::covariance is the 6x6
//   covariance of xi = (tx, ty, tz, rx, ry, rz) of that transform, r the rotation vector.
// - Body frame: FRD (x forward, y right, z down), MAVLink's MAV_FRAME_BODY_FRD.
// - Extrinsic X = (R_bc, p_bc): the camera axes expressed in body axes (columns of R_bc) and
//   the camera's position in the body frame [m]. Default: camera looking forward at the body
//   origin, R_bc = [[0,0,1],[1,0,0],[0,1,0]], p_bc = 0.
// - Body motion over a pair: dT_b = X dT_c X^-1 (the motion of the body origin, lever arm
//   included), covariance S_b = J S_c J^T, J = [[R_bc, dR_b [p_bc]x Jr(r_b) R_bc], [0, R_bc]]
//   (Jr the right Jacobian of SO(3); at small rotations J = [[R, [p]x R], [0, R]]).
//   Because the lever arm is already removed, the autopilot's own camera offset and
//   orientation (ArduPilot VISO_POS_X/Y/Z, VISO_ORIENT) must be left at zero.
// - Local frame: MAV_FRAME_LOCAL_FRD, the body frame at the first frame. The pose is
//   T_lb(k) = T_lb(k-1) dT_b. Its covariance P, for left perturbations (dp, dth) (position
//   added in the local frame, rotation exp(dth) R), is propagated as
//   P_k = A P_{k-1} A^T + B S_b B^T, A = [[I, -[R_{k-1} t_b]x], [0, I]],
//   B = [[R_{k-1}, 0], [0, R_k Jr(r_b)]]. It is then expressed in MAVLink's parameters
//   (x, y, z, roll, pitch, yaw), ZYX Euler angles R = Rz(yaw) Ry(pitch) Rx(roll), through the
//   Jacobian of (roll, pitch, yaw) with respect to dth (singular at pitch = +-90 deg).
//   With keyframes (PairResult::keyframe), P is instead the chain's: P at the frame the chain
//   began, carried (A over the way since), plus the keyframes' covariance of the motion since
//   then. Over one view it holds still where integrated pairs would grow with every frame;
//   it grows at keyframe switches and is integrated as above across a failed pair.
//   Camera odometry sees no gravity: the local frame is level only if the vehicle was level
//   at the first frame, or if level_initial_attitude() was given its roll and pitch then
//   (the autopilot's ATTITUDE): the pose starts at Ry(pitch) Rx(roll) instead of identity.
// - Velocities (ODOMETRY) are the mean over the pair, expressed in the body frame at the
//   current frame like VISION_POSITION_DELTA.position_delta: v = dR_b^T t_b / dt [m/s],
//   angular rate w = r_b / dt [rad/s] (a rotation vector is the same in both body frames),
//   dt = (t_curr_ns - t_prev_ns) 1e-9 s. Their covariance is the linearisation of those.
//   Why the current frame: the message's q is the current attitude, and a receiver turns
//   the velocity into the local frame with it; in the previous body frame the velocity
//   would be off by the pair's whole rotation.
// - Covariances go out as the 21-float upper triangle, row-major.
// - A failed pair (status != Ok, or a non-finite or non-causal result): ODOMETRY carries no
//   pose: position, attitude, velocities, rates and both covariances are NaN, quality = -1
//   (an autopilot skips a non-finite sample; a finite one would be fused as a frozen pose
//   whatever its quality, see mavlink_odometry.cpp); no VISION_POSITION_DELTA. The integrated
//   pose is not moved (the motion is unknown) and is sent again from the next good pair.
// - reset_counter (uint8, wraps): +1 at the first good pair after failed ones (the pose has
//   missed an unknown motion) and +1 at note_sensor_reset() (sensor re-opened). The pose then
//   continues from the last pose sent, and P from the last P: after a reset the local frame
//   is the one in which that holds, its relation to the frame before the reset unknown.
// - quality (1..100; 0 would mean unknown, -1 failed): from the translation standard
//   deviation of the pair's body motion s_t = sqrt(trace(S_b[0:3,0:3]) / 3),
//   quality = clamp(round(100 (1 - s_t / s_fail)), 1, 100).
// - VISION_POSITION_DELTA.confidence [%]: ArduPilot's EKF3 turns it into a velocity noise
//   linearly, velErr = EK3_VIS_VERR_MIN + (EK3_VIS_VERR_MAX - EK3_VIS_VERR_MIN)(1 - confidence/100)
//   (AP_NavEKF3_Measurements.cpp, writeBodyFrameOdom); we invert that for s_v = s_t / dt:
//   confidence = clamp(100 (VERR_MAX - s_v) / (VERR_MAX - VERR_MIN), 0, 100).
// - HEARTBEAT: MAV_TYPE_ONBOARD_CONTROLLER, MAV_AUTOPILOT_INVALID, base_mode 0, custom_mode 0;
//   system_status STANDBY before the first pair, ACTIVE while the latest pair is good,
//   CRITICAL after a failed one (tracking lost).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <optional>

#include "rgbd_odometry/core/camera_mount.hpp"
#include "rgbd_odometry/core/geometry.hpp"
#include "rgbd_odometry/link/mavlink.hpp"
#include "rgbd_odometry/core/pair_result.hpp"

namespace rgbdo {

struct MavlinkOdometryConfig {
  CameraExtrinsic extrinsic;
  double quality_sigma_fail_m = 0.02;  // s_t at which quality reaches its floor of 1
  // ArduPilot EK3_VIS_VERR_MIN / EK3_VIS_VERR_MAX (defaults 0.1 and 0.9 m/s, AP_NavEKF3.cpp);
  // set them to the autopilot's values so that confidence means the noise we estimated.
  double velocity_error_min_mps = 0.1;
  double velocity_error_max_mps = 0.9;
  // VISION_POSITION_DELTA composes consecutive good pairs until they span at least this long:
  // ArduPilot's EKF3 drops deltas closer together than sensorIntervalMin_ms (50 ms,
  // AP_NavEKF3_Measurements.cpp writeBodyFrameOdom), which at 30 Hz is every other one.
  double delta_min_interval_s = 0;
};

// The pair's motion of the body origin, in the previous body frame.
struct BodyMotion {
  Eigen::Isometry3d T_prev_curr = Eigen::Isometry3d::Identity();
  Matrix6d covariance = Matrix6d::Zero();  // of xi = (t, rotvec)
  double dt_s = 0;
};

// ---- the linearisations, exposed for their tests -----------------------------------------
// (so3_right_jacobian is in core/geometry.hpp.)
// d xi_b / d xi_c at the given motion, for dT_b = X dT_c X^-1.
Matrix6d camera_to_body_jacobian(const CameraExtrinsic& X, const Eigen::Isometry3d& T_body_prev_curr);
BodyMotion body_motion(const PairResult& pair, const CameraExtrinsic& X);
// d (roll, pitch, yaw) / d dth for the left perturbation exp(dth) R.
Eigen::Matrix3d euler_zyx_jacobian_left(const Eigen::Matrix3d& R);
// Covariance of (v, w) = (dR^T t / dt, r / dt) from that of xi = (t, r).
Matrix6d velocity_covariance(const BodyMotion& m);
// Row-major upper triangle, MAVLink's 21-float covariance layout.
std::array<float, 21> upper_triangle(const Matrix6d& C);

class OdometryMessageBuilder {
 public:
  explicit OdometryMessageBuilder(const MavlinkOdometryConfig& config = {});

  // One pair result, in capture order.
  void add(const PairResult& pair);
  // The sensor was closed and opened again: whatever comes next is not connected to the
  // pose so far. Announces the jump at once; failed pairs before it need no second one.
  void note_sensor_reset() {
    ++reset_counter_;
    pending_reset_ = false;
  }

  // The messages for the latest pair. ODOMETRY is nullopt only before the first pair;
  // VISION_POSITION_DELTA is nullopt unless the latest pair was good and the good pairs since
  // the last delta span delta_min_interval_s (a failed pair starts the composition again).
  [[nodiscard]] std::optional<mavlink::Odometry> odometry() const;
  [[nodiscard]] std::optional<mavlink::VisionPositionDelta> vision_position_delta() const;
  [[nodiscard]] mavlink::Heartbeat heartbeat() const;

  // Before the first good pair only: the body's roll and pitch at the first frame (yaw 0), so
  // that the local frame is level (its z along gravity) however the vehicle stood. False
  // (nothing changed) once a pose has been integrated.
  bool level_initial_attitude(double roll_rad, double pitch_rad);
  bool has_pose() const { return has_pose_; }

  const Eigen::Isometry3d& pose() const { return T_local_body_; }  // body in the local frame
  const Matrix6d& pose_covariance() const { return P_; }           // of the left (dp, dth)
  std::uint8_t reset_counter() const { return reset_counter_; }

 private:
  enum class Tracking { NotStarted, Ok, Lost };

  static bool usable(const PairResult& pair);
  void integrate(const BodyMotion& m);
  void anchor_to_chain(const KeyframeLink& link);
  std::int8_t quality(const BodyMotion& m) const;
  float confidence(double translation_variance_trace, double dt_s) const;
  void compose_delta(const BodyMotion& m);

  MavlinkOdometryConfig config_;
  Eigen::Isometry3d T_local_body_ = Eigen::Isometry3d::Identity();
  Matrix6d P_ = Matrix6d::Zero();
  // Where the keyframes' current chain began (PairResult::keyframe): its position and P then.
  struct ChainOrigin {
    Eigen::Vector3d position;
    Matrix6d P;
  };
  std::optional<ChainOrigin> chain_;
  std::uint8_t reset_counter_ = 0;  // uint8 arithmetic: wraps at 256 like the field
  bool pending_reset_ = false;      // failed pairs seen since the last good one
  bool has_pose_ = false;           // a good pair has been integrated
  Tracking tracking_ = Tracking::NotStarted;
  // The latest pair.
  std::int64_t t_prev_ns_ = 0, t_curr_ns_ = 0;
  BodyMotion last_motion_;
  // VISION_POSITION_DELTA's composition of good pairs: motion, covariance of its right
  // perturbation (rho, phi) (core/geometry.hpp), span, and the stamp it starts at.
  Eigen::Isometry3d delta_T_ = Eigen::Isometry3d::Identity();
  Matrix6d delta_P_ = Matrix6d::Zero();
  double delta_dt_s_ = 0;
  std::int64_t delta_start_ns_ = 0;
  bool delta_due_ = false;  // the composition spans delta_min_interval_s: sent with this pair
};

}  // namespace rgbdo
