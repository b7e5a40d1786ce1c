#include "rgbd_odometry/core/settings.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>

namespace rgbdo {
namespace {

double parse_number(const std::string& key, const std::string& text) {
  double value = 0;
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc() || ptr != end || !std::isfinite(value))
    throw ConfigError("config key '" + key + "': expected a number, got '" + text + "'");
  return value;
}

void check_range(const Setting& p, double value) {
  if (p.above_min && !(value > p.min && value <= p.max)) {
    std::ostringstream msg;
    msg << "config key '" << p.key << "': value " << value << " is outside (" << p.min << ", " << p.max
        << "]: it must be above " << p.min << " (at " << p.min << " the estimate is singular)";
    throw ConfigError(msg.str());
  }
  if (!(value >= p.min && value <= p.max)) {
    std::ostringstream msg;
    msg << "config key '" << p.key << "': value " << value << " is outside [" << p.min << ", "
        << p.max << "]";
    throw ConfigError(msg.str());
  }
}

void check_integral(const Setting& p, double value) {
  if (value != std::floor(value))
    throw ConfigError("config key '" + p.key + "': expected a whole number, got " +
                      std::to_string(value));
}

std::string shortest(double v) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char text[32];
  const auto [end, ec] = std::to_chars(text, text + sizeof text, v);  // the shortest that reads back exactly
  return ec == std::errc() ? std::string(text, end) : std::to_string(v);
}

}  // namespace

Setting* find_setting(SettingsTable& table, const std::string& key) {
  for (auto& p : table)
    if (p.key == key) return &p;
  return nullptr;
}

void set_setting_text(Setting& p, const std::string& text) {
  std::visit(
      [&](auto* target) {
        using T = std::remove_pointer_t<decltype(target)>;
        if constexpr (std::is_same_v<T, std::string>) {
          *target = text;
        } else if constexpr (std::is_same_v<T, bool>) {
          if (text == "true" || text == "1" || text == "on") *target = true;
          else if (text == "false" || text == "0" || text == "off") *target = false;
          else throw ConfigError("config key '" + p.key + "': expected true/false, got '" + text + "'");
        } else {
          const double v = parse_number(p.key, text);
          check_range(p, v);
          if constexpr (!std::is_same_v<T, double>) check_integral(p, v);
          *target = static_cast<T>(v);
        }
      },
      p.target);
}

bool set_setting(SettingsTable& table, const std::string& key, const ConfigValue& value) {
  Setting* p = find_setting(table, key);
  if (!p) return false;
  std::visit(
      [&](auto* target) {
        using T = std::remove_pointer_t<decltype(target)>;
        if constexpr (std::is_same_v<T, std::string>) {
          if (!std::holds_alternative<std::string>(value))
            throw ConfigError("config key '" + p->key + "': expected a string");
          *target = std::get<std::string>(value);
        } else if constexpr (std::is_same_v<T, bool>) {
          if (const auto* text = std::get_if<std::string>(&value)) {
            set_setting_text(*p, *text);
          } else {
            const double v = std::get<double>(value);
            if (v != std::floor(v)) throw ConfigError("config key '" + p->key + "': expected true/false");
            set_setting_text(*p, std::to_string(static_cast<long long>(v)));
          }
        } else {
          if (!std::holds_alternative<double>(value))
            throw ConfigError("config key '" + p->key + "': expected a number");
          const double v = std::get<double>(value);
          check_range(*p, v);
          if constexpr (!std::is_same_v<T, double>) check_integral(*p, v);
          *target = static_cast<T>(v);
        }
      },
      p->target);
  return true;
}

void check_ranges(const SettingsTable& table) {
  for (const Setting& p : table) {
    std::visit(
        [&](auto* target) {
          using T = std::remove_pointer_t<decltype(target)>;
          if constexpr (!std::is_same_v<T, std::string> && !std::is_same_v<T, bool>)
            check_range(p, static_cast<double>(*target));
        },
        p.target);
  }
}

std::vector<ConfigKeyInfo> describe_settings(const SettingsTable& table) {
  std::vector<ConfigKeyInfo> out;
  for (const Setting& p : table) {
    ConfigKeyInfo info;
    info.key = p.key;
    info.unit = std::string(p.unit);
    info.help = std::string(p.help);
    std::visit(
        [&](auto* target) {
          using T = std::remove_pointer_t<decltype(target)>;
          if constexpr (std::is_same_v<T, std::string>) {
            info.kind = ConfigKeyInfo::Kind::Text;
            info.value = *target;
          } else if constexpr (std::is_same_v<T, bool>) {
            info.kind = ConfigKeyInfo::Kind::Boolean;
            info.value = *target ? "true" : "false";
          } else {
            info.kind = std::is_same_v<T, double> ? ConfigKeyInfo::Kind::Number : ConfigKeyInfo::Kind::Integer;
            info.value = std::is_same_v<T, double> ? shortest(static_cast<double>(*target)) : std::to_string(*target);
            // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on the chained '+'.
            info.range = p.above_min ? "(" : "[";
            info.range.append(shortest(p.min)).append(", ").append(shortest(p.max)).append("]");
          }
        },
        p.target);
    out.push_back(std::move(info));
  }
  return out;
}

bool listed(std::span<const std::string_view> names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

std::string joined(std::span<const std::string_view> names) {
  std::string text;
  for (const auto name : names) text += (text.empty() ? "" : ", ") + std::string(name);
  return text;
}


}  // namespace rgbdo
