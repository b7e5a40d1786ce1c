#include "rgbd_odometry/core/time_format.hpp"

#include <cinttypes>
#include <cstdio>
#include <string>

namespace rgbdo {

std::string format_seconds(std::int64_t t_ns) {
  const bool negative = t_ns < 0;
  const std::uint64_t magnitude = negative ? static_cast<std::uint64_t>(-(t_ns + 1)) + 1 : static_cast<std::uint64_t>(t_ns);
  const std::uint64_t micros = (magnitude + 500) / 1000;
  char buf[48];
  std::snprintf(buf, sizeof buf, "%s%" PRIu64 ".%06" PRIu64, negative ? "-" : "", micros / 1000000, micros % 1000000);
  return buf;
}

}  // namespace rgbdo
