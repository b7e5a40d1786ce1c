#pragma once
// The virtual sensor's URI (virtual_sensor_driver.cpp describes each option), parsed apart
// from the driver so that the fuzz target (test/fuzz/fuzz_uris.cpp) reaches the same code.
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <set>
#include <string>
#include <string_view>

#include "rgbd_odometry/core/uri_query.hpp"

namespace rgbdo::virtual_sensor {

inline constexpr std::string_view kScheme = "rgbdo-virtual:";

struct Options {
  std::string directory;
  double rate = 1.0;
  std::set<int> drop;
  int stall_at = -1, stall_ms = 0;
  int disconnect_at = -1;
  int reconnect_ms = -1;  // -1: never comes back
  int loops = 1;
};

inline bool parse_int(std::string_view text, int& out) {
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), out);
  return ec == std::errc() && end == text.data() + text.size();
}

// False for anything but a well-formed URI with a directory and a finite positive rate.
inline bool parse_uri(const std::string& uri, Options& o) {
  if (uri.rfind(kScheme, 0) != 0) return false;
  const std::string rest = uri.substr(kScheme.size());
  const auto q = rest.find('?');
  o.directory = rest.substr(0, q);
  if (q == std::string::npos) return !o.directory.empty();
  bool ok = true;
  const auto malformed =
      for_each_query_pair(std::string_view(rest).substr(q + 1), [&](std::string_view key, std::string_view value) {
        if (key == "rate") {
          const std::string text(value);
          char* end = nullptr;
          o.rate = std::strtod(text.c_str(), &end);
          ok = ok && !text.empty() && end == text.c_str() + text.size();
        } else if (key == "drop") {
          while (!value.empty()) {
            const auto comma = value.find(',');
            int i = 0;
            ok = ok && parse_int(value.substr(0, comma), i);
            o.drop.insert(i);
            value = comma == std::string_view::npos ? std::string_view{} : value.substr(comma + 1);
          }
        } else if (key == "stall") {
          const auto colon = value.find(':');
          ok = ok && colon != std::string_view::npos && parse_int(value.substr(0, colon), o.stall_at) &&
               parse_int(value.substr(colon + 1), o.stall_ms) && o.stall_ms >= 0;
        } else if (key == "disconnect") {
          ok = ok && parse_int(value, o.disconnect_at);
        } else if (key == "reconnect") {
          ok = ok && parse_int(value, o.reconnect_ms);
        } else if (key == "loop") {
          ok = ok && parse_int(value, o.loops) && o.loops >= 1;
        } else if (key != "id") {
          ok = false;
        }
      });
  // An infinite or NaN rate would make every frame due at once or never.
  return ok && !malformed && !o.directory.empty() && std::isfinite(o.rate) && o.rate > 0;
}

}  // namespace rgbdo::virtual_sensor
