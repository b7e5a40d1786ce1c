#pragma once
// What the pipeline hands its outputs (log, link, console, evaluation) for every frame.
#include <cstdint>
#include <string>

#include "rgbd_odometry/core/pair_result.hpp"

namespace rgbdo {

struct PairOutput {
  bool has_pair = false;                  // false for the very first frame
  PairResult result;                      // when has_pair
  std::int64_t t_frame_ns = 0;            // colour capture time of the newer frame (its source's timeline)
  std::int64_t t_depth_ns = 0;            // capture time of the depth image paired with it
  std::int64_t host_lead_ns = 0;          // see RgbdFrame
  std::int64_t t_frame_host_ns() const { return t_frame_ns - host_lead_ns; }  // as stamped in the pair
  std::int64_t t_capture_host_ns = 0;     // steady clock, see CapturedFrame
  int skipped = 0;                        // frames skipped between the pair's two frames
  double latency_ms = 0;                  // capture to hand-over to the outputs
  std::string frame_problem;              // the newer frame's failure, as the source put it
};

}  // namespace rgbdo
