#pragma once
// The machinery of settings, and no settings of its own: each layer defines the settings of
// its components beside them (pipeline/pipeline_config.hpp, sensor/sensor_config.hpp, ...) and
// registers its keys into a table here, each key with its unit, range and one line of help.
// The program's configuration (app/config.hpp) is the tables of every layer in one; a file,
// the command line's overrides and --print-config all go through a table, so a key is named,
// checked and documented in one place.
#include <cstdint>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace rgbdo {

// A bad configuration value or file; the message names the key or file.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One value as a configuration file holds it: a number or a text.
using ConfigValue = std::variant<double, std::string>;

// One settable key: where its value lives and the range it must lie in.
struct Setting {
  std::string key;        // "section.name"
  std::string_view unit;  // empty: none
  std::string_view help;  // one line: what it does, what its special values mean
  std::variant<int*, double*, bool*, std::string*, std::uint64_t*> target;
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  // Where zero is singular (a variance, a weight), min itself is refused: (min, max].
  bool above_min = false;
};

using SettingsTable = std::vector<Setting>;

// The key's entry, or null.
Setting* find_setting(SettingsTable& table, const std::string& key);

// Sets a key from a file's value after checking its type and range (ConfigError naming the
// key); false when there is no such key.
bool set_setting(SettingsTable& table, const std::string& key, const ConfigValue& value);

// Sets a key from its text form (the command line's KEY=VALUE) after checking type and range.
void set_setting_text(Setting& setting, const std::string& text);

// Throws ConfigError naming the first key whose value lies outside its range.
void check_ranges(const SettingsTable& table);

// One key as the configuration reference and --print-config show it.
struct ConfigKeyInfo {
  enum class Kind { Number, Integer, Boolean, Text };
  std::string key;    // "section.name" ("seed" has no section)
  std::string unit;   // empty: none
  std::string help;   // one line
  std::string range;  // "[16, 8192]", "(0, 100]"; empty for booleans and texts
  std::string value;  // as a file writes it (texts unquoted)
  Kind kind = Kind::Number;
};
// Every key in the table's order, with the values it points at.
std::vector<ConfigKeyInfo> describe_settings(const SettingsTable& table);

// For a key that names one of a list: whether `name` is on it, and the list as text.
bool listed(std::span<const std::string_view> names, const std::string& name);
std::string joined(std::span<const std::string_view> names);

}  // namespace rgbdo
