#pragma once
// Capture times as people and the TUM tools read them.
#include <cstdint>
#include <string>

namespace rgbdo {

// Formats integer nanoseconds as seconds with 6 decimals, exactly (no double rounding).
std::string format_seconds(std::int64_t t_ns);

}  // namespace rgbdo
