// The ARM cost model's report: reads the stage counts of two replays of the same recording
// (stage_cost_plugin.cpp output), a short and a long one, and prints what one frame costs on
// the target per stage, the slope between the two runs (start-up cancels out), and the frame
// rate that implies on the Odroid-XU3's Cortex-A15 under stated assumptions. With a budget
// file it fails (exit 1) when a stage or the whole frame costs more than its budget.
//
//   arm_cost_report SHORT.txt SHORT_FRAMES LONG.txt LONG_FRAMES [BUDGET.txt]
//
// BUDGET.txt: lines "STAGE MILLION_INSTRUCTIONS_PER_FRAME" ("frame" for the whole frame),
// '#' comments.
#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <initializer_list>
#include <iostream>
#include <map>
#include <sstream>
#include <string>

#include "rgbd_odometry/core/cost_stage.hpp"

namespace {

using rgbdo::CostStage;
using rgbdo::kCostStageCount;
using rgbdo::kCostStageNames;

struct StageCounts {
  std::array<double, kCostStageCount> instructions{};
  std::array<double, kCostStageCount> entries{};
};

[[noreturn]] void fail(const std::string& message) {
  std::cerr << "arm_cost_report: " << message << "\n";
  std::exit(2);
}

StageCounts read_counts(const std::string& path) {
  std::ifstream in(path);
  if (!in) fail("cannot read " + path);
  StageCounts c;
  std::array<bool, kCostStageCount> seen{};
  std::string name;
  double instructions = 0, entries = 0;
  while (in >> name >> instructions >> entries) {
    std::size_t s = 0;
    while (s < kCostStageCount && name != kCostStageNames[s]) ++s;
    if (s == kCostStageCount) fail(path + ": unknown stage '" + name + "'");
    c.instructions[s] = instructions;
    c.entries[s] = entries;
    seen[s] = true;
  }
  for (std::size_t s = 0; s < kCostStageCount; ++s)
    if (!seen[s]) fail(path + ": no count for stage '" + std::string(kCostStageNames[s]) + "'");
  return c;
}

std::map<std::string, double> read_budget(const std::string& path) {
  std::ifstream in(path);
  if (!in) fail("cannot read budget " + path);
  std::map<std::string, double> budget;
  for (std::string line; std::getline(in, line);) {
    if (const auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::istringstream words(line);
    std::string name;
    double millions = 0;
    if (!(words >> name)) continue;
    if (!(words >> millions)) fail(path + ": no number for '" + name + "'");
    budget[name] = millions;
  }
  return budget;
}

bool is_target_work(std::size_t s) {
  // Decoding PNG files is the recording's cost, not the sensor's: a live frame arrives decoded.
  return s != static_cast<std::size_t>(CostStage::Decode);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 5 && argc != 6) fail("usage: arm_cost_report SHORT.txt SHORT_FRAMES LONG.txt LONG_FRAMES [BUDGET.txt]");
  const StageCounts a = read_counts(argv[1]), b = read_counts(argv[3]);
  const double frames_a = std::atof(argv[2]), frames_b = std::atof(argv[4]);
  if (!(frames_b > frames_a && frames_a > 0)) fail("the long run must have more frames than the short one");
  const auto mask = static_cast<std::size_t>(CostStage::Mask);
  if (a.entries[mask] != frames_a || b.entries[mask] != frames_b)
    fail("the runs extracted " + std::to_string(a.entries[mask]) + " and " + std::to_string(b.entries[mask]) +
         " frames, not " + argv[2] + " and " + argv[4] + " (were the markers on? RGBDO_COST_MARKERS=1)");
  const double n = frames_b - frames_a;

  std::printf("ARM instructions per frame (armhf build, slope between %g and %g frames; PNG decoding excluded)\n",
              frames_a, frames_b);
  double frame = 0;
  std::array<double, kCostStageCount> per_frame{};
  for (std::size_t s = 0; s < kCostStageCount; ++s) {
    per_frame[s] = (b.instructions[s] - a.instructions[s]) / n;
    if (is_target_work(s)) frame += per_frame[s];
  }
  for (std::size_t s = 0; s < kCostStageCount; ++s)
    std::printf("  %-12s %8.2f M%s\n", kCostStageNames[s], per_frame[s] / 1e6,
                is_target_work(s) ? "" : "   (excluded: decoding a recorded frame)");
  std::printf("  %-12s %8.2f M\n", "frame", frame / 1e6);

  // The assumptions, stated: Exynos 5422 big cluster at 2.0 GHz; a Cortex-A15 retires 1 to
  // 1.5 instructions per cycle on such code (memory stalls not modelled); the frame's stages
  // run one after the other on one core (extraction and estimation overlap on two cores
  // with runtime.processing_threads = 2, so the rate is then set by the larger half).
  const double clock_hz = 2.0e9;
  const auto sum = [&](std::initializer_list<CostStage> stages) {
    double t = 0;
    for (const CostStage s : stages) t += per_frame[static_cast<std::size_t>(s)];
    return t;
  };
  const double extraction = sum({CostStage::Convert, CostStage::Mask, CostStage::Pyramid, CostStage::Corners, CostStage::Detect, CostStage::Geometry});
  const double estimation = sum({CostStage::Match, CostStage::PointPairs, CostStage::Ransac, CostStage::Covariance});
  const double other = per_frame[static_cast<std::size_t>(CostStage::Other)];
  const double two_cores = std::max(extraction, estimation) + other;
  // With runtime.extraction_threads = 3, the levels' corners and descriptors (tasks per
  // pyramid level) are split three ways; level 0 holds ~31 % of the pixels, so three is
  // about the most a level split gains. The rest of extraction stays on its thread.
  const double split = sum({CostStage::Corners, CostStage::Detect});
  const double extraction_3 = extraction - split + split / 3;
  const double latency_3 = extraction_3 + estimation + other;  // one frame, through both threads
  std::printf("estimated Odroid-XU3 (Cortex-A15 @ 2.0 GHz, memory stalls not modelled):\n");
  for (const double ipc : {1.0, 1.5}) {
    std::printf("  IPC %.1f: one core %5.1f frames/s; extraction and estimation on two cores %5.1f frames/s\n", ipc,
                ipc * clock_hz / frame, ipc * clock_hz / two_cores);
    std::printf("           + 3 extraction threads (4 A15 cores) %5.1f frames/s, latency %4.1f ms per frame\n",
                ipc * clock_hz / (std::max(extraction_3, estimation) + other), 1e3 * latency_3 / (ipc * clock_hz));
  }
  std::printf("per_frame_M %.2f\n", frame / 1e6);

  if (argc == 6) {
    int over = 0;
    for (const auto& [name, millions] : read_budget(argv[5])) {
      double value = -1;
      if (name == "frame") value = frame;
      for (std::size_t s = 0; s < kCostStageCount; ++s)
        if (name == kCostStageNames[s]) value = per_frame[s];
      if (value < 0) fail(std::string(argv[5]) + ": unknown stage '" + name + "'");
      const bool ok = value <= millions * 1e6;
      over += !ok;
      std::printf("budget %-12s %8.2f M of %8.2f M  %s\n", name.c_str(), value / 1e6, millions,
                  ok ? "ok" : "OVER BUDGET");
    }
    std::printf("%d over budget\n", over);
    return over == 0 ? 0 : 1;
  }
  return 0;
}
