#pragma once
// The odometry files' settings (log.*) and their keys (core/settings.hpp).
#include <limits>

#include "rgbd_odometry/core/settings.hpp"

namespace rgbdo {

struct LogConfig {
  // The odometry log and trajectory files of this and earlier runs together (FILE, FILE.1,
  // ...: io/rotating_file.hpp), in MB; the oldest runs' files go first. ~100 MB an hour at 30 Hz.
  double max_total_mb = 1024;
};

// The keys log.* into `table`, pointing into c.
inline void add_log_settings(LogConfig& c, SettingsTable& table) {
  table.insert(table.end(), {
      {"log.max_total_mb", "MB", "the odometry log and trajectory of this and earlier runs together; the oldest go first", &c.max_total_mb, 0.01, 1e7},
  });
}

}  // namespace rgbdo
