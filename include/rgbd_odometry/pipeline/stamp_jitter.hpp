#pragma once
// How well a frame's colour-to-depth capture-time offset is known, from the streams' own
// frame intervals. Both streams run at a fixed hardware period, so the scatter of successive
// intervals around their median is the scatter of the time stamps: an interval is the
// difference of two stamps, var(interval) = 2 var(stamp). The offset t_colour - t_depth
// carries both streams' stamp errors: sigma^2 = var(colour stamp) + var(depth stamp).
// Intervals far from the median (a skipped frame, two colour frames sharing a depth image)
// are not stamp scatter and are left out. Recorded sequences stamped on arrival (TUM) show
// milliseconds; a live sensor's hardware clock, microseconds.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include "rgbd_odometry/pipeline/backproject.hpp"

namespace rgbdo {

class StampJitter {
 public:
  // Two consecutive frames of the stream.
  void add(const FrameTimes& prev, const FrameTimes& curr) {
    colour_.push(static_cast<double>(curr.t_colour_ns - prev.t_colour_ns) * 1e-9);
    depth_.push(static_cast<double>(curr.t_depth_ns - prev.t_depth_ns) * 1e-9);
  }
  // 0 until a few intervals are known.
  double offset_sigma_s() const { return std::sqrt(colour_.stamp_variance() + depth_.stamp_variance()); }

 private:
  static constexpr int kIntervals = 128;  // about 4 s at 30 Hz
  struct Intervals {
    std::array<double, kIntervals> v{};
    int count = 0, next = 0;
    void push(double x) {
      v[static_cast<size_t>(next)] = x;
      next = (next + 1) % kIntervals;
      count = std::min(count + 1, kIntervals);
    }
    double stamp_variance() const {
      if (count < 4) return 0;
      // Summed in sorted order, not the ring's: the same intervals give the same bits wherever
      // the ring happens to start (a looped recording repeats its results exactly).
      std::array<double, kIntervals> sorted = v;
      std::sort(sorted.begin(), sorted.begin() + count);
      const double median = sorted[static_cast<size_t>(count / 2)];
      double sum = 0;
      int used = 0;
      for (int i = 0; i < count; ++i) {
        const double d = sorted[static_cast<size_t>(i)] - median;
        if (std::abs(d) > 0.5 * median) continue;
        sum += d * d;
        ++used;
      }
      return used > 1 ? sum / used / 2 : 0;
    }
  };
  Intervals colour_, depth_;
};

}  // namespace rgbdo
