#pragma once
// The real-time pipeline's threads (runtime.*) and their keys (core/settings.hpp).
#include <limits>
#include <string>
#include <vector>

#include "rgbd_odometry/core/settings.hpp"

namespace rgbdo {

struct RuntimeConfig {
  // 1: extraction and pair estimation in one thread; 2: extraction of frame k+1 overlaps
  // the matching/RANSAC/covariance of frame k.
  int processing_threads = 2;
  // Threads that extract one frame (GRID_ORB's pyramid levels split between them: the same
  // result on any number): the extraction thread and extraction_threads - 1 helpers started
  // once. On the XU3 the big cluster (CPUs 4-7) has room for 3 next to capture/estimation.
  int extraction_threads = 1;
  // CPUs to pin the threads to, "" for none. A comma list taken in the order capture,
  // extraction, estimation, output (wrapping round), e.g. "4,5,6,7" for the XU3's A15 cores.
  std::string cpu_affinity;
};

// The keys runtime.* into `table`, pointing into c.
inline void add_runtime_settings(RuntimeConfig& c, SettingsTable& table) {
  table.insert(table.end(), {
      {"runtime.processing_threads", "", "1: extraction and estimation in one thread; 2: overlapped", &c.processing_threads, 1, 2},
      {"runtime.extraction_threads", "", "threads extracting one frame (the same result on any number)", &c.extraction_threads, 1, 8},
      {"runtime.cpu_affinity", "", "CPUs for capture, extraction, estimation, output (wrapping), e.g. \"4,5,6,7\"; empty: none", &c.cpu_affinity},
  });
}

// runtime.cpu_affinity as CPU numbers; throws ConfigError on a malformed list.
std::vector<int> parse_cpu_list(const std::string& text);

// Throws ConfigError naming the first key whose value does not fit.
inline void validate_runtime(const RuntimeConfig& c) { (void)parse_cpu_list(c.cpu_affinity); }

}  // namespace rgbdo
