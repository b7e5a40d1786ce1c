#include "rgbd_odometry/core/cost_stage.hpp"

#include <sys/syscall.h>
#include <unistd.h>

#include <cstdlib>

namespace rgbdo {
namespace {

// Read once, before main: the hot path only tests a bool.
const bool g_markers_on = [] {
  const char* v = std::getenv("RGBDO_COST_MARKERS");
  return v != nullptr && v[0] == '1' && v[1] == '\0';
}();

}  // namespace

void mark_cost_stage(CostStage stage) noexcept {
  if (!g_markers_on) return;
  syscall(SYS_getpid, static_cast<long>(kCostMarkerMagic), static_cast<long>(stage));
}

}  // namespace rgbdo
