#include "rgbd_odometry/runtime/runtime_config.hpp"

#include <charconv>
#include <sstream>

namespace rgbdo {

std::vector<int> parse_cpu_list(const std::string& text) {
  std::vector<int> cpus;
  std::stringstream list(text);
  for (std::string item; std::getline(list, item, ',');) {
    int cpu = -1;
    const char* end = item.data() + item.size();
    auto [ptr, ec] = std::from_chars(item.data(), end, cpu);
    if (ec != std::errc() || ptr != end || cpu < 0 || cpu > 1023)
      throw ConfigError("config key 'runtime.cpu_affinity': expected CPU numbers like \"4,5,6,7\", got '" + text + "'");
    cpus.push_back(cpu);
  }
  return cpus;
}

}  // namespace rgbdo
