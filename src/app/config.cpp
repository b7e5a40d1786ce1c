#include "rgbd_odometry/app/config.hpp"

namespace rgbdo {

SettingsTable config_table(Config& config) {
  SettingsTable table;
  add_pipeline_settings(config, table);
  add_sensor_settings(config.sensor, table);
  add_runtime_settings(config.runtime, table);
  add_log_settings(config.log, table);
  add_body_settings(config.body, table);
  add_link_settings(config.link, table);
  add_seed_setting(config, table);
  return table;
}

bool set_config_value(Config& config, const std::string& key, const ConfigValue& value) {
  SettingsTable table = config_table(config);
  return set_setting(table, key, value);
}

void apply_overrides(Config& config, const std::vector<std::string>& assignments) {
  SettingsTable table = config_table(config);
  for (const auto& a : assignments) {
    const auto eq = a.find('=');
    if (eq == std::string::npos)
      throw ConfigError("override '" + a + "': expected KEY=VALUE (for example ransac.max_iterations=300)");
    const std::string key = a.substr(0, eq);
    Setting* setting = find_setting(table, key);
    if (!setting) throw ConfigError("override '" + a + "': unknown key '" + key + "'");
    set_setting_text(*setting, a.substr(eq + 1));
  }
}

std::vector<std::string> config_keys() {
  Config c;
  std::vector<std::string> keys;
  for (const Setting& s : config_table(c)) keys.push_back(s.key);
  return keys;
}

std::vector<ConfigKeyInfo> describe_config(const Config& config) {
  Config copy = config;
  return describe_settings(config_table(copy));
}

void validate(const Config& config) {
  Config copy = config;
  check_ranges(config_table(copy));
  validate_pipeline(config);
  validate_runtime(config.runtime);
  validate_link(config.link);
}

}  // namespace rgbdo
