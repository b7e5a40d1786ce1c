// --set KEY=VALUE overrides, one per line, then validation: a Config or a ConfigError.
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_input.hpp"
#include "rgbd_odometry/app/config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace rgbdo;
  std::vector<std::string> assignments;
  std::string_view text = fuzz::text_of(data, size);
  while (!text.empty()) {
    const auto end = text.find('\n');
    assignments.emplace_back(text.substr(0, end));
    text = end == std::string_view::npos ? std::string_view{} : text.substr(end + 1);
  }
  Config c;
  try {
    apply_overrides(c, assignments);
    validate(c);
  } catch (const ConfigError&) {
  }
  return 0;
}
