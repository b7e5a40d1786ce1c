#pragma once
// The MAVLink link's settings (link.*) and their keys (core/settings.hpp).
#include <limits>
#include <optional>
#include <string>

#include "rgbd_odometry/core/settings.hpp"

namespace rgbdo {

// The MAVLink 2 link to the flight computer (deploy/README.md#flight-computer-link-mavlink).
struct LinkConfig {
  std::string uri;  // udp://HOST:PORT, udpin://[ADDR]:PORT or serial:///dev/ttyX[:BAUD]; empty: no link
  int system_id = 1;  // the vehicle's: a companion computer shares its autopilot's system id
  bool odometry = true;                 // send ODOMETRY (#331): PX4 EKF2, ArduPilot EKF3
  bool vision_position_delta = false;   // send VISION_POSITION_DELTA (#11011): ArduPilot
  double quality_sigma_fail_m = 0.02;   // frame-to-frame sigma_t at which quality reaches 1 %
  // ArduPilot's EK3_VIS_VERR_MIN / _MAX: confidence maps onto that velocity-noise range.
  double velocity_error_min_mps = 0.1;
  double velocity_error_max_mps = 0.9;
  // The autopilot followed (its HEARTBEAT): only this system id; 0 = the first one heard.
  int autopilot_system_id = 0;
  // No frame from the autopilot for this long: reported gone. Above the 1 s heartbeat period
  // (PX4 and ArduPilot also send other streams) and short enough to tell within 2 s.
  double autopilot_timeout_s = 1.5;
  // Our TIMESYNC requests while an autopilot is up (the autopilot's own are always answered); 0: none.
  double timesync_rate_hz = 1.0;
  // Answers slower than this round trip are not used for the offset (error bound rtt/2).
  double timesync_max_rtt_ms = 100;
  // The EKF origin "LATITUDE_DEG, LONGITUDE_DEG, ALTITUDE_M" (WGS84, altitude AMSL), sent as
  // SET_GPS_GLOBAL_ORIGIN and SET_HOME_POSITION once the autopilot is heard: ArduPilot's EKF3
  // uses no external position without an origin. Empty: none sent. In a file also as a list
  // [lat, lon, alt].
  std::string ekf_origin;
  // The followed autopilot's ATTITUDE asked for at this rate (MAV_CMD_SET_MESSAGE_INTERVAL),
  // for its gyro rates (latency.*); 0: not asked, whatever it streams is used.
  double attitude_rate_hz = 50;
  // VISION_POSITION_DELTA: pairs composed until they span at least this long. ArduPilot's EKF3
  // drops deltas closer together than its sensorIntervalMin_ms (50 ms, AP_NavEKF3).
  double delta_min_interval_ms = 50;
};

// link.ekf_origin parsed: nullopt when empty; throws ConfigError naming the key otherwise.
struct GeoPoint {
  double latitude_deg = 0, longitude_deg = 0, altitude_m = 0;
};
std::optional<GeoPoint> parse_ekf_origin(const std::string& text);


void add_link_settings(LinkConfig& c, SettingsTable& table);
// Throws ConfigError naming the first key whose value does not fit the others, link.uri
// included (its syntax is the transport's: link/transport.hpp parse_link_uri).
void validate_link(const LinkConfig& c);

}  // namespace rgbdo
