#pragma once
// What the program prints: one line per pair while it runs, and the end-of-run summary
// (failures by status, frames skipped and dropped, latency, stage times, and the accuracy
// and covariance consistency against ground truth when the source has it).
#include <cstddef>
#include <iosfwd>
#include <string>

#include "rgbd_odometry/core/pair_result.hpp"
#include "rgbd_odometry/eval/evaluate.hpp"
#include "rgbd_odometry/app/config.hpp"
#include "rgbd_odometry/runtime/realtime.hpp"

namespace rgbdo {

std::string pair_line(const PairResult& r, std::size_t index, bool verbose);

// What the summary tells of the pairs besides their accuracy.
struct PairTallies {
  StageTimes total;       // summed over the good pairs
  int timed = 0;          // good pairs
  int rematched = 0;      // windowed matching fell short (PairResult::rematched)
  int depth_refined = 0;  // the depth alignment was fused in (PairResult::depth_points > 0)
  int depth_trusted = 0;  // of those, at the learnt trust (PairResult::depth_trusted)
  long point_pairs = 0;   // over the good pairs
  long tracked = 0;       // of those point pairs, tracked below a pixel (PairResult::tracked)
  int keyframes_made = 0, keyframe_returns = 0;  // PairResult::keyframe
  int keyframe_measured = 0;                     // good pairs measured against their keyframe
  SensorEstimates sensor;  // as learnt by the last good pair
  void add(const PairResult& r);
};

void print_summary(std::ostream& out, const AccuracySummary& s, bool with_groundtruth, const PairTallies& tallies,
                   const RealtimeStats& run);

// When the frames were taken, as measured against a gyro (nothing without one): the latency
// applied to every motion, the camera's mount the gyro shows, and the autopilot settings that
// follow (live: the capture-to-output latency measured in this run).
void print_capture_timing(std::ostream& out, const CaptureTiming& timing, const Config& config, const RealtimeStats& run,
                          bool live);

}  // namespace rgbdo
