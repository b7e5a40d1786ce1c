#pragma once
// The one host clock every layer measures with: std::chrono::steady_clock as integer
// nanoseconds. Capture times of live frames are mapped onto it (sensor/device_clock.hpp), the
// link stamps its reports with it, and latency is the difference of two readings of it.
#include <chrono>
#include <cmath>
#include <cstdint>

namespace rgbdo {

inline std::int64_t steady_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// Milliseconds elapsed on that clock since `start` (stage timings).
inline double ms_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

// A duration in seconds (a configuration's) as the clock's integer nanoseconds, rounded.
inline std::int64_t seconds_to_ns(double s) { return static_cast<std::int64_t>(std::llround(s * 1e9)); }

}  // namespace rgbdo
