// The ARM cost model's report: reads the stage counts of two replays of the same recording
// (stage_cost_plugin.cpp output), a short and a long one, and prints what one frame costs on
// the target per stage, the slope between the two runs (start-up cancels out), and the frame
// rate that implies on the Odroid-XU3's Cortex-A15 under stated assumptions; then how the
// cost spreads over the long run's frames (median, 90th percentile, worst), since a frame rate
// is kept by the worst frames, not the average. With a budget file it fails (exit 1) when a
// stage, the whole frame or the worst frame costs more than its budget.
//
//   arm_cost_report SHORT.txt SHORT_FRAMES LONG.txt LONG_FRAMES [BUDGET.txt]
//
// BUDGET.txt: lines "STAGE MILLION_INSTRUCTIONS_PER_FRAME" ("frame" for the whole frame's
// average, "worst_frame" for the costliest frame's work), '#' comments.
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
#include <vector>

#include "rgbd_odometry/core/cost_stage.hpp"

namespace {

using rgbdo::CostStage;
using rgbdo::kCostStageCount;
using rgbdo::kCostStageNames;

struct StageCounts {
  std::array<double, kCostStageCount> instructions{};
  std::array<double, kCostStageCount> entries{};
  std::vector<std::array<double, kCostStageCount>> frame_starts;  // every stage's count at each frame's start, and at exit
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
  for (std::string line; std::getline(in, line);) {
    std::istringstream words(line);
    std::string name;
    double instructions = 0, entries = 0;
    if (!(words >> name)) continue;
    if (name == "frame_start") {
      std::array<double, kCostStageCount> totals{};
      for (double& n : totals)
        if (!(words >> n)) fail(path + ": a frame_start line without a count for every stage");
      c.frame_starts.push_back(totals);
      continue;
    }
    if (!(words >> instructions >> entries)) fail(path + ": no counts for '" + name + "'");
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

// A frame's own work: the target's, less waits and output (other), which follow the run's wall
// time rather than the frame.
bool is_frame_work(std::size_t s) { return is_target_work(s) && s != static_cast<std::size_t>(CostStage::Other); }

// What each frame after the first cost, stage by stage (the first has no pair to estimate):
// the counts between its start and the next frame's, the last frame's up to the exit.
std::vector<std::array<double, kCostStageCount>> frame_costs(const StageCounts& c, double frames) {
  if (c.frame_starts.size() != static_cast<std::size_t>(frames) + 1)
    fail("the long run recorded " + std::to_string(c.frame_starts.size()) + " frame starts, not " +
         std::to_string(static_cast<long>(frames)) + " and the exit (a plugin without per-frame counts?)");
  std::vector<std::array<double, kCostStageCount>> costs;
  for (std::size_t k = 1; k + 1 < c.frame_starts.size(); ++k) {
    std::array<double, kCostStageCount> cost{};
    for (std::size_t s = 0; s < kCostStageCount; ++s) cost[s] = c.frame_starts[k + 1][s] - c.frame_starts[k][s];
    costs.push_back(cost);
  }
  return costs;
}

// The q-quantile of `v` (nearest rank).
double quantile(std::vector<double> v, double q) {
  const auto k = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5);
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
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

  // How the cost spreads over frames: the worst against the median, and the stages that make
  // the difference. Per frame only the processing thread is followed; the work on other
  // threads (the reader's conversion: fixed by the image size) is added as its average, the
  // slope's frame work less the processing thread's over the same frames.
  const auto costs = frame_costs(b, frames_b);
  std::vector<double> work;
  for (const auto& cost : costs) {
    double w = 0;
    for (std::size_t s = 0; s < kCostStageCount; ++s)
      if (is_frame_work(s)) w += cost[s];
    work.push_back(w);
  }
  const auto first_of_slope = static_cast<std::ptrdiff_t>(frames_a) - 1;  // costs[k] is frame k + 2
  double thread_mean = 0;
  for (auto w = work.begin() + first_of_slope; w != work.end(); ++w) thread_mean += *w;
  thread_mean /= static_cast<double>(work.end() - (work.begin() + first_of_slope));
  const double other_threads = std::max(0.0, frame - per_frame[static_cast<std::size_t>(CostStage::Other)] - thread_mean);
  const std::size_t worst = static_cast<std::size_t>(std::max_element(work.begin(), work.end()) - work.begin());
  const double worst_frame = work[worst] + other_threads, median_frame = quantile(work, 0.5) + other_threads;
  std::printf("frames 2-%g of the long run, waits and output excluded (other threads' %.2f M a frame as their "
              "average): median %.2f M, 90th percentile %.2f M, worst %.2f M (frame %zu, %.2f x the median)\n",
              frames_b, other_threads / 1e6, median_frame / 1e6, (quantile(work, 0.9) + other_threads) / 1e6,
              worst_frame / 1e6, worst + 2, worst_frame / median_frame);
  std::printf("  the worst frame's stages against each stage's median:");
  for (std::size_t s = 0; s < kCostStageCount; ++s) {
    if (!is_frame_work(s)) continue;
    std::vector<double> stage;
    for (const auto& cost : costs) stage.push_back(cost[s]);
    const double median = quantile(stage, 0.5);
    if (costs[worst][s] - median > 0.05 * (worst_frame - median_frame))
      std::printf(" %s %.2f (%.2f)", kCostStageNames[s], costs[worst][s] / 1e6, median / 1e6);
  }
  std::printf(" M\n");

  if (argc == 6) {
    int over = 0;
    for (const auto& [name, millions] : read_budget(argv[5])) {
      double value = -1;
      if (name == "frame") value = frame;
      if (name == "worst_frame") value = worst_frame;
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
