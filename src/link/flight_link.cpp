#include "rgbd_odometry/link/flight_link.hpp"

#include <cmath>
#include <iomanip>
#include <sstream>

namespace rgbdo {
namespace {

constexpr std::int64_t kHeartbeatPeriodNs = 1'000'000'000;
constexpr double kDegToRad = M_PI / 180.0;
constexpr double kFrameRateHz = 30.0;  // the sensor's rate, for the serial capacity check

MavlinkOdometryConfig message_config(const Config& c) {
  MavlinkOdometryConfig m;
  m.extrinsic = extrinsic_from(c.body);
  m.quality_sigma_fail_m = c.link.quality_sigma_fail_m;
  m.velocity_error_min_mps = c.link.velocity_error_min_mps;
  m.velocity_error_max_mps = c.link.velocity_error_max_mps;
  return m;
}

}  // namespace

CameraExtrinsic extrinsic_from(const BodyConfig& body) {
  CameraExtrinsic x;
  const Eigen::Matrix3d mount = (Eigen::AngleAxisd(body.camera_yaw_deg * kDegToRad, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(body.camera_pitch_deg * kDegToRad, Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(body.camera_roll_deg * kDegToRad, Eigen::Vector3d::UnitX()))
                                    .toRotationMatrix();
  x.R_body_camera = mount * CameraExtrinsic::forward_looking_rotation();
  x.p_body_camera_m = Eigen::Vector3d(body.camera_x_m, body.camera_y_m, body.camera_z_m);
  return x;
}

FlightLink::FlightLink(const Config& config)
    : config_(config.link), options_(parse_link_uri(config.link.uri)), link_(open_link(options_)),
      builder_(message_config(config)),
      framer_(static_cast<std::uint8_t>(config.link.system_id), mavlink::kMavCompIdVisualInertialOdometry) {}

void FlightLink::send(std::size_t bytes) { (void)link_->send(std::span<const std::uint8_t>(buffer_.data(), bytes)); }

void FlightLink::send_pair(const PairResult& pair) {
  if (pair.status == Status::SensorLost) builder_.note_sensor_reset();
  builder_.add(pair);
  if (config_.odometry) {
    if (const auto odometry = builder_.odometry()) send(framer_.encode(*odometry, buffer_));
  }
  if (config_.vision_position_delta) {
    if (const auto delta = builder_.vision_position_delta()) send(framer_.encode(*delta, buffer_));
  }
}

void FlightLink::tick(std::int64_t now_ns) {
  if (now_ns < next_heartbeat_ns_) return;
  next_heartbeat_ns_ = now_ns + kHeartbeatPeriodNs;
  send(framer_.encode(builder_.heartbeat(), buffer_));
}

std::string FlightLink::startup_report() const {
  std::ostringstream s;
  s << "MAVLink 2 to " << link_->description() << " as system " << config_.system_id << " component "
    << static_cast<int>(mavlink::kMavCompIdVisualInertialOdometry) << ":" << (config_.odometry ? " ODOMETRY" : "")
    << (config_.vision_position_delta ? " VISION_POSITION_DELTA" : "") << " per frame pair, HEARTBEAT at 1 Hz";
  if (const auto* serial = std::get_if<SerialLinkOptions>(&options_)) {
    // Wire bytes per pair: each message's full payload plus 12 bytes of framing.
    const std::size_t bytes = (config_.odometry ? mavlink::Odometry::kPayloadBytes + 12 : 0) +
                              (config_.vision_position_delta ? mavlink::VisionPositionDelta::kPayloadBytes + 12 : 0);
    s << "\n" << serial_capacity(serial->baud, bytes, kFrameRateHz).message;
  }
  if (!link_->stats().link_up && !link_->last_problem().empty()) s << "\nnot up yet: " << link_->last_problem();
  return s.str();
}

std::string FlightLink::news() {
  const LinkStats st = link_->stats();
  if (st.problem_reports == problems_seen_) return {};
  problems_seen_ = st.problem_reports;
  return link_->last_problem();
}

}  // namespace rgbdo
