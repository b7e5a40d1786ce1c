#pragma once
// What the program prints: one line per pair while it runs, and the end-of-run summary
// (failures by status, frames skipped and dropped, latency, stage times, and the accuracy
// and covariance consistency against ground truth when the source has it).
#include <cstddef>
#include <iosfwd>
#include <string>

#include "rgbd_odometry/core/pair_result.hpp"
#include "rgbd_odometry/io/evaluate.hpp"
#include "rgbd_odometry/runtime/realtime.hpp"

namespace rgbdo {

std::string pair_line(const PairResult& r, std::size_t index, bool verbose);

// `total` sums the stage times of `timed_pairs` good pairs; `rematched_pairs` counts the pairs
// whose windowed matching fell short (PairResult::rematched).
void print_summary(std::ostream& out, const AccuracySummary& s, bool with_groundtruth, const StageTimes& total,
                   int timed_pairs, int rematched_pairs, const RealtimeStats& run);

}  // namespace rgbdo
