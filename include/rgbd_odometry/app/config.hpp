#pragma once
// The program's configuration: every layer's settings in one, and its keys as one table made of
// the tables each layer registers (core/settings.hpp). Loaded and validated once at start-up (a
// YAML file through app/config_file.hpp, then command-line overrides). A component takes its
// own layer's part: the pipeline a PipelineConfig (which a Config is), the runtime its
// RuntimeConfig, the link its LinkConfig, the sensor its SensorConfig.
#include <string>
#include <vector>

#include "rgbd_odometry/core/settings.hpp"
#include "rgbd_odometry/io/log_config.hpp"
#include "rgbd_odometry/link/link_config.hpp"
#include "rgbd_odometry/pipeline/pipeline_config.hpp"
#include "rgbd_odometry/runtime/runtime_config.hpp"
#include "rgbd_odometry/sensor/sensor_config.hpp"

namespace rgbdo {

struct Config : PipelineConfig {
  SensorConfig sensor;
  RuntimeConfig runtime;
  LogConfig log;
  LinkConfig link;
};

// Every key, section by section (camera ... latency, sensor, runtime, log, body, link, seed),
// pointing into config.
SettingsTable config_table(Config& config);

// Sets "section.key" from a file's value after checking its type and range (ConfigError
// naming the key); false when there is no such key.
bool set_config_value(Config& config, const std::string& key, const ConfigValue& value);

// Applies "section.key=value" overrides (the command line's), in order.
void apply_overrides(Config& config, const std::vector<std::string>& assignments);

// Every key a configuration file or override may set, for help texts and docs.
std::vector<std::string> config_keys();

// Every key in the table's order, with config's values (deploy/config/README.md, --print-config).
std::vector<ConfigKeyInfo> describe_config(const Config& config);

// Throws ConfigError naming the first invalid key: each layer's checks of its own settings.
void validate(const Config& config);

}  // namespace rgbdo
