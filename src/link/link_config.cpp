#include "rgbd_odometry/link/link_config.hpp"

#include "rgbd_odometry/link/transport.hpp"

#include <charconv>
#include <cmath>
#include <sstream>
#include <vector>

namespace rgbdo {

void add_link_settings(LinkConfig& c, SettingsTable& table) {
  table.insert(table.end(), {
      {"link.uri", "", "udp://HOST:PORT, udpin://[ADDR]:PORT or serial:///dev/ttyX[:BAUD]; empty: no link", &c.uri},
      {"link.system_id", "", "our MAVLink system id: the vehicle's", &c.system_id, 1, 255},
      {"link.odometry", "", "send ODOMETRY (PX4 EKF2, ArduPilot EKF3)", &c.odometry},
      {"link.vision_position_delta", "", "send VISION_POSITION_DELTA instead (ArduPilot; needs link.odometry false)", &c.vision_position_delta},
      {"link.quality_sigma_fail_m", "m", "pair sigma_t at which ODOMETRY quality reaches 1 %", &c.quality_sigma_fail_m, 1e-4, 10},
      {"link.velocity_error_min_mps", "m/s", "ArduPilot EK3_VIS_VERR_MIN: confidence maps onto [min, max]", &c.velocity_error_min_mps, 0.0, 100, true},  // 0: an exact velocity to the EKF
      {"link.velocity_error_max_mps", "m/s", "ArduPilot EK3_VIS_VERR_MAX", &c.velocity_error_max_mps, 0.0, 100},
      {"link.autopilot_system_id", "", "follow only this system's autopilot; 0: the first heard", &c.autopilot_system_id, 0, 255},
      {"link.autopilot_timeout_s", "s", "nothing heard this long: the autopilot is reported gone", &c.autopilot_timeout_s, 0.2, 60},
      {"link.timesync_rate_hz", "Hz", "our TIMESYNC requests while an autopilot is up; 0: none", &c.timesync_rate_hz, 0.0, 20},
      {"link.timesync_max_rtt_ms", "ms", "slower answers are not used for our clock offset", &c.timesync_max_rtt_ms, 0.1, 10000},
      {"link.ekf_origin", "deg, deg, m", "LATITUDE, LONGITUDE, ALTITUDE (AMSL) sent as SET_GPS_GLOBAL_ORIGIN and SET_HOME_POSITION (ArduPilot needs it without GPS); empty: none", &c.ekf_origin},
      {"link.attitude_rate_hz", "Hz", "the autopilot's ATTITUDE (its gyro rates, for latency.*) asked for at this rate; 0: not asked", &c.attitude_rate_hz, 0.0, 500},
      {"link.delta_min_interval_ms", "ms", "VISION_POSITION_DELTA composed over at least this (ArduPilot drops closer ones: 50)", &c.delta_min_interval_ms, 0.0, 1000},
  });
}

void validate_link(const LinkConfig& c) {
  if (c.velocity_error_min_mps >= c.velocity_error_max_mps)
    throw ConfigError("config key 'link.velocity_error_min_mps': must be below link.velocity_error_max_mps");
  if (!c.uri.empty() && !c.odometry && !c.vision_position_delta)
    throw ConfigError("config key 'link.odometry': a link with neither ODOMETRY nor VISION_POSITION_DELTA sends nothing");
  if (c.odometry && c.vision_position_delta)
    throw ConfigError(
        "config key 'link.vision_position_delta': with link.odometry also on, ArduPilot's EKF3 would fuse the same "
        "motion twice (ODOMETRY as external navigation, VISION_POSITION_DELTA as body odometry) and PX4 reads no "
        "VISION_POSITION_DELTA: choose one (for ArduPilot's deltas set link.odometry: false)");
  (void)parse_ekf_origin(c.ekf_origin);
  if (!c.uri.empty()) {
    try {
      (void)parse_link_uri(c.uri);
    } catch (const LinkError& e) {
      throw ConfigError(std::string("config key 'link.uri': ") + e.what());
    }
  }
}

std::optional<GeoPoint> parse_ekf_origin(const std::string& text) {
  if (text.find_first_not_of(" \t") == std::string::npos) return std::nullopt;
  const auto bad = [&](const std::string& why) {
    return ConfigError("config key 'link.ekf_origin': " + why + " (expected \"LATITUDE_DEG, LONGITUDE_DEG, ALTITUDE_M\", got '" +
                       text + "')");
  };
  std::vector<double> values;
  std::stringstream list(text);
  for (std::string item; std::getline(list, item, ',');) {
    const auto first = item.find_first_not_of(" \t"), last = item.find_last_not_of(" \t");
    if (first == std::string::npos) throw bad("an empty value");
    item = item.substr(first, last - first + 1);
    double v = 0;
    const char* end = item.data() + item.size();
    const auto [ptr, ec] = std::from_chars(item.data(), end, v);
    if (ec != std::errc() || ptr != end || !std::isfinite(v)) throw bad("'" + item + "' is not a number");
    values.push_back(v);
  }
  if (values.size() != 3) throw bad("3 values needed");
  if (std::abs(values[0]) > 90) throw bad("latitude outside [-90, 90] degrees");
  if (std::abs(values[1]) > 180) throw bad("longitude outside [-180, 180] degrees");
  if (values[2] < -1000 || values[2] > 10000) throw bad("altitude outside [-1000, 10000] m");
  return GeoPoint{values[0], values[1], values[2]};
}

}  // namespace rgbdo
