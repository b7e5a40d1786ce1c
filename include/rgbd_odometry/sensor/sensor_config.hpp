#pragma once
// A live OpenNI2 sensor's settings (sensor.*) and their keys (core/settings.hpp).
#include <limits>
#include <string>

#include "rgbd_odometry/core/settings.hpp"

namespace rgbdo {

// A live OpenNI2 sensor (ignored for recorded sources).
struct SensorConfig {
  int fps = 30;
  bool registration = true;     // hardware depth-to-colour registration (the paper's set-up)
  int frame_timeout_ms = 2000;  // no frame for this long: the sensor is reported lost
  int pairing_wait_ms = 70;     // how long a colour frame waits for its depth frame
  // After a loss, try to re-open every reconnect_interval_ms for reconnect_timeout_s seconds
  // (negative: for ever, as on the vehicle; 0: stop at the first loss).
  double reconnect_timeout_s = -1;
  int reconnect_interval_ms = 500;
  std::string record_oni;  // non-empty: also record the sensor's streams to this .oni file
};

// The keys sensor.* into `table`, pointing into c.
inline void add_sensor_settings(SensorConfig& c, SettingsTable& table) {
  table.insert(table.end(), {
      {"sensor.fps", "Hz", "live sensor frame rate", &c.fps, 1, 120},
      {"sensor.registration", "", "hardware depth-to-colour registration", &c.registration},
      {"sensor.frame_timeout_ms", "ms", "no frame this long: the sensor is reported lost", &c.frame_timeout_ms, 100, 600000},
      {"sensor.pairing_wait_ms", "ms", "how long a colour frame waits for a depth frame after it", &c.pairing_wait_ms, 0, 10000},
      {"sensor.reconnect_timeout_s", "s", "after a loss, re-open for this long; < 0: for ever (the vehicle), 0: stop at the first loss", &c.reconnect_timeout_s, -1, 1e9},
      {"sensor.reconnect_interval_ms", "ms", "time between re-open attempts", &c.reconnect_interval_ms, 10, 600000},
      {"sensor.record_oni", "", "non-empty: also record the sensor's streams to this .oni file", &c.record_oni},
  });
}

}  // namespace rgbdo
