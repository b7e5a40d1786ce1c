#pragma once
// Which recorded frame each frame of a live run through the virtual sensor is. Live times are
// the device's clock mapped onto the host's (a constant offset over a short run), so the
// intervals from the first live frame are the recording's intervals from the frame it was.
// That first frame need not be the recording's first: a reader that started late lost some.
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "rgbd_odometry/io/tum_sequence.hpp"

namespace rgbdo {

// The recorded frame of each live colour time, in order; empty when no run of recorded frames
// fits all of them (to the device clock's 1 us steps).
inline std::vector<size_t> recorded_frame_of(const std::vector<std::int64_t>& live_colour_ns, const TumSequence& seq) {
  if (live_colour_ns.empty()) return {};
  constexpr std::int64_t kToleranceNs = 2000;
  for (size_t first = 0; first < seq.frames.size(); ++first) {
    std::vector<size_t> index;
    size_t k = first;
    for (const std::int64_t t : live_colour_ns) {
      const std::int64_t since_first = t - live_colour_ns.front();
      while (k < seq.frames.size() &&
             seq.frames[k].t_colour_ns - seq.frames[first].t_colour_ns < since_first - kToleranceNs)
        ++k;
      if (k == seq.frames.size() ||
          std::llabs(seq.frames[k].t_colour_ns - seq.frames[first].t_colour_ns - since_first) > kToleranceNs)
        break;
      index.push_back(k);
    }
    if (index.size() == live_colour_ns.size()) return index;
  }
  return {};
}

}  // namespace rgbdo
