#include "rgbd_odometry/link/mavlink_odometry.hpp"

#include <algorithm>
#include <cmath>

namespace rgbdo {
namespace {

Eigen::Isometry3d body_from_camera(const CameraExtrinsic& X) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = X.R_body_camera;
  T.translation() = X.p_body_camera_m;
  return T;
}

std::uint64_t to_usec(std::int64_t t_ns) { return t_ns <= 0 ? 0 : static_cast<std::uint64_t>(t_ns / 1000); }

}  // namespace

Matrix6d camera_to_body_jacobian(const CameraExtrinsic& X, const Eigen::Isometry3d& T_body_prev_curr) {
  // t_b = R t_c + (I - dR_b) p and r_b = R r_c (conjugation keeps the angle, turns the axis).
  // Only the lever-arm term depends on the rotation: d(-exp(r) p)/dr = exp(r) [p]x Jr(r).
  const Eigen::Matrix3d& R = X.R_body_camera;
  const Eigen::Matrix3d& dR = T_body_prev_curr.linear();
  Matrix6d J = Matrix6d::Zero();
  J.topLeftCorner<3, 3>() = R;
  J.topRightCorner<3, 3>() = dR * skew(X.p_body_camera_m) * so3_right_jacobian(rotation_vector(dR)) * R;
  J.bottomRightCorner<3, 3>() = R;
  return J;
}

BodyMotion body_motion(const PairResult& pair, const CameraExtrinsic& X) {
  const Eigen::Isometry3d T_bc = body_from_camera(X);
  BodyMotion m;
  m.T_prev_curr = T_bc * pair.T_prev_curr * T_bc.inverse();
  const Matrix6d J = camera_to_body_jacobian(X, m.T_prev_curr);
  m.covariance = J * pair.covariance * J.transpose();
  m.dt_s = static_cast<double>(pair.t_curr_ns - pair.t_prev_ns) * 1e-9;
  return m;
}

Eigen::Matrix3d euler_zyx_jacobian_left(const Eigen::Matrix3d& R) {
  // Left perturbation exp(dth) R: dth is the angular velocity in the local frame, which the
  // Euler rates make as w = Rz Ry e_x droll + Rz e_y dpitch + e_z dyaw. This is the inverse
  // of that 3x3 map; it divides by cos(pitch).
  const Eigen::Vector3d e = euler_zyx(R);
  const double cp = std::cos(e.y()), tp = std::tan(e.y());
  const double cy = std::cos(e.z()), sy = std::sin(e.z());
  Eigen::Matrix3d G;
  G << cy / cp, sy / cp, 0,  //
      -sy, cy, 0,            //
      cy * tp, sy * tp, 1;
  return G;
}

Matrix6d velocity_covariance(const BodyMotion& m) {
  const Eigen::Matrix3d& dR = m.T_prev_curr.linear();
  const Eigen::Vector3d t_curr = dR.transpose() * m.T_prev_curr.translation();  // t_b in the current body frame
  // d(dR(r)^T t)/dr = [dR^T t]x Jr(r); the rate r/dt depends on r alone.
  Matrix6d G = Matrix6d::Zero();
  G.topLeftCorner<3, 3>() = dR.transpose();
  G.topRightCorner<3, 3>() = skew(t_curr) * so3_right_jacobian(rotation_vector(dR));
  G.bottomRightCorner<3, 3>().setIdentity();
  return G * m.covariance * G.transpose() / (m.dt_s * m.dt_s);
}

std::array<float, 21> upper_triangle(const Matrix6d& C) {
  std::array<float, 21> out{};
  std::size_t k = 0;
  for (int row = 0; row < 6; ++row)
    for (int col = row; col < 6; ++col) out[k++] = static_cast<float>(C(row, col));
  return out;
}

OdometryMessageBuilder::OdometryMessageBuilder(const MavlinkOdometryConfig& config) : config_(config) {}

bool OdometryMessageBuilder::usable(const PairResult& pair) {
  // Ok promises a finite motion and covariance; a pair that breaks the promise, or whose
  // clock runs backwards (no velocity), is sent as failed rather than as nonsense.
  return pair.status == Status::Ok && pair.t_curr_ns > pair.t_prev_ns && pair.T_prev_curr.matrix().allFinite() &&
         pair.covariance.allFinite();
}

void OdometryMessageBuilder::add(const PairResult& pair) {
  t_prev_ns_ = pair.t_prev_ns;
  t_curr_ns_ = pair.t_curr_ns;
  if (delta_due_ || !usable(pair)) {  // sent, or broken by an unknown motion: start again
    delta_T_ = Eigen::Isometry3d::Identity();
    delta_P_.setZero();
    delta_dt_s_ = 0;
    delta_due_ = false;
  }
  if (!usable(pair)) {
    tracking_ = Tracking::Lost;
    pending_reset_ = true;
    return;
  }
  last_motion_ = body_motion(pair, config_.extrinsic);
  if (pending_reset_) {
    ++reset_counter_;
    pending_reset_ = false;
  }
  integrate(last_motion_);
  if (pair.keyframe.id != 0) anchor_to_chain(pair.keyframe);
  has_pose_ = true;
  compose_delta(last_motion_);
  tracking_ = Tracking::Ok;
}

bool OdometryMessageBuilder::level_initial_attitude(double roll_rad, double pitch_rad) {
  if (has_pose_) return false;
  T_local_body_.linear() = (Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitY()) *
                            Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitX()))
                               .toRotationMatrix();
  return true;
}

void OdometryMessageBuilder::compose_delta(const BodyMotion& m) {
  // Right perturbations compose as the evaluation's windows do: the earlier part's is carried
  // through the later motion, Ad(T_m^-1), and the later part's added.
  if (delta_dt_s_ == 0) delta_start_ns_ = t_prev_ns_;
  const Matrix6d carry = se3_adjoint(m.T_prev_curr.inverse());
  delta_P_ = carry * delta_P_ * carry.transpose() + right_perturbation_covariance(m.T_prev_curr, m.covariance);
  delta_T_ = delta_T_ * m.T_prev_curr;
  delta_dt_s_ += m.dt_s;
  // A microsecond's slack: 30 Hz stamps rounded to the microsecond must not miss 50 ms.
  delta_due_ = delta_dt_s_ >= config_.delta_min_interval_s - 1e-6;
}

void OdometryMessageBuilder::integrate(const BodyMotion& m) {
  const Eigen::Matrix3d R_before = T_local_body_.linear();
  const Eigen::Vector3d t_b = m.T_prev_curr.translation();
  T_local_body_ = T_local_body_ * m.T_prev_curr;
  // Re-orthonormalise: thousands of products drift off SO(3) in floating point.
  T_local_body_.linear() = Eigen::Quaterniond(T_local_body_.linear()).normalized().toRotationMatrix();

  Matrix6d A = Matrix6d::Identity();
  A.topRightCorner<3, 3>() = -skew(R_before * t_b);  // an earlier attitude error swings the step
  Matrix6d B = Matrix6d::Zero();
  B.topLeftCorner<3, 3>() = R_before;
  B.bottomRightCorner<3, 3>() = T_local_body_.linear() * so3_right_jacobian(rotation_vector(m.T_prev_curr.linear()));
  P_ = A * P_ * A.transpose() + B * m.covariance * B.transpose();
  P_ = 0.5 * (P_ + P_.transpose());  // keep rounding from making it asymmetric over a long run
}

void OdometryMessageBuilder::anchor_to_chain(const KeyframeLink& link) {
  if (link.chain_started || !chain_.has_value()) {
    chain_ = ChainOrigin{T_local_body_.translation(), P_};
    return;
  }
  if (!link.pose_covariance.allFinite()) return;  // keep the integrated P rather than nonsense
  // The pose is the chain's origin times the motion since: an error of the origin swings the
  // whole way from there (A, as in integrate()), and the keyframes' covariance of the motion
  // since, a right perturbation in the camera frame, turns into the body frame (Ad of the
  // extrinsic) and then into left perturbations (dp, dth) = (R rho, R phi).
  Matrix6d A = Matrix6d::Identity();
  A.topRightCorner<3, 3>() = -skew(T_local_body_.translation() - chain_->position);
  Matrix6d B = Matrix6d::Zero();
  B.topLeftCorner<3, 3>() = T_local_body_.linear();
  B.bottomRightCorner<3, 3>() = T_local_body_.linear();
  const Matrix6d to_body = se3_adjoint(body_from_camera(config_.extrinsic));
  P_ = A * chain_->P * A.transpose() + B * to_body * link.pose_covariance * to_body.transpose() * B.transpose();
  P_ = 0.5 * (P_ + P_.transpose());
}

std::int8_t OdometryMessageBuilder::quality(const BodyMotion& m) const {
  const double sigma_t = std::sqrt(std::max(0.0, m.covariance.topLeftCorner<3, 3>().trace() / 3));
  double q = std::round(100 * (1 - sigma_t / config_.quality_sigma_fail_m));
  if (!(q >= 1)) q = 1;  // also NaN: 0 would claim "unknown", and this pair is known
  return static_cast<std::int8_t>(std::min(q, 100.0));
}

float OdometryMessageBuilder::confidence(double translation_variance_trace, double dt_s) const {
  // A rotation keeps the trace: that of the right perturbation's rho is that of t's.
  const double sigma_v = std::sqrt(std::max(0.0, translation_variance_trace / 3)) / dt_s;
  const double lo = config_.velocity_error_min_mps, hi = config_.velocity_error_max_mps;
  double c = 100 * (hi - sigma_v) / (hi - lo);
  if (!(c >= 0)) c = 0;
  return static_cast<float>(std::min(c, 100.0));
}

std::optional<mavlink::Odometry> OdometryMessageBuilder::odometry() const {
  if (tracking_ == Tracking::NotStarted) return std::nullopt;
  mavlink::Odometry o;
  o.time_usec = to_usec(t_curr_ns_);
  o.frame_id = mavlink::kMavFrameLocalFrd;
  o.child_frame_id = mavlink::kMavFrameBodyFrd;
  o.reset_counter = reset_counter_;
  o.estimator_type = mavlink::kMavEstimatorTypeVision;
  if (tracking_ != Tracking::Ok) {
    // No pose at all, never the last one: PX4 reads quality only when EKF2_EV_QMIN > 0 (its
    // default is 0, ev_control.cpp) and would fuse a frozen position while the vehicle moves.
    // A non-finite position stops its EV position fusion (PX4_ISFINITE(ev_sample.pos(0)) and
    // measurement.isAllFinite(), ev_pos_control.cpp) without declaring the sensor faulty.
    constexpr float kNaN = mavlink::kUnknown;
    o.x = o.y = o.z = kNaN;
    o.q = {kNaN, kNaN, kNaN, kNaN};
    o.quality = -1;  // pose, velocities and both covariances keep their NaN defaults
    return o;
  }
  const Eigen::Vector3d p = T_local_body_.translation();
  o.x = static_cast<float>(p.x());
  o.y = static_cast<float>(p.y());
  o.z = static_cast<float>(p.z());
  Eigen::Quaterniond q(T_local_body_.linear());
  if (q.w() < 0) q.coeffs() = -q.coeffs();  // one sign for one attitude: logs compare directly
  o.q = {static_cast<float>(q.w()), static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z())};
  Matrix6d G = Matrix6d::Identity();
  G.bottomRightCorner<3, 3>() = euler_zyx_jacobian_left(T_local_body_.linear());
  o.pose_covariance = upper_triangle(G * P_ * G.transpose());
  const Eigen::Matrix3d& dR = last_motion_.T_prev_curr.linear();
  const Eigen::Vector3d v = dR.transpose() * last_motion_.T_prev_curr.translation() / last_motion_.dt_s;
  const Eigen::Vector3d w = rotation_vector(dR) / last_motion_.dt_s;
  o.vx = static_cast<float>(v.x());
  o.vy = static_cast<float>(v.y());
  o.vz = static_cast<float>(v.z());
  o.rollspeed = static_cast<float>(w.x());
  o.pitchspeed = static_cast<float>(w.y());
  o.yawspeed = static_cast<float>(w.z());
  o.velocity_covariance = upper_triangle(velocity_covariance(last_motion_));
  o.quality = quality(last_motion_);
  return o;
}

std::optional<mavlink::VisionPositionDelta> OdometryMessageBuilder::vision_position_delta() const {
  if (tracking_ != Tracking::Ok || !delta_due_) return std::nullopt;
  mavlink::VisionPositionDelta d;
  d.time_usec = to_usec(t_curr_ns_);
  // A difference of the two stamps: consecutive messages' deltas then add up to their stamps.
  d.time_delta_usec = to_usec(t_curr_ns_) - to_usec(delta_start_ns_);
  const Eigen::Matrix3d& dR = delta_T_.linear();
  const Eigen::Vector3d r = rotation_vector(dR);
  const Eigen::Vector3d t_curr = dR.transpose() * delta_T_.translation();
  d.angle_delta = {static_cast<float>(r.x()), static_cast<float>(r.y()), static_cast<float>(r.z())};
  d.position_delta = {static_cast<float>(t_curr.x()), static_cast<float>(t_curr.y()), static_cast<float>(t_curr.z())};
  d.confidence = confidence(delta_P_.topLeftCorner<3, 3>().trace(), delta_dt_s_);
  return d;
}

mavlink::Heartbeat OdometryMessageBuilder::heartbeat() const {
  mavlink::Heartbeat h;
  h.type = mavlink::kMavTypeOnboardController;
  h.autopilot = mavlink::kMavAutopilotInvalid;
  h.base_mode = 0;
  h.custom_mode = 0;
  switch (tracking_) {
    case Tracking::NotStarted: h.system_status = mavlink::kMavStateStandby; break;
    case Tracking::Ok: h.system_status = mavlink::kMavStateActive; break;
    case Tracking::Lost: h.system_status = mavlink::kMavStateCritical; break;
  }
  return h;
}

}  // namespace rgbdo
