#pragma once
// What the running process holds, from Linux's /proc/self: resident memory, open file
// descriptors, threads. The summary compares a snapshot after warm-up with one at the end,
// so that a long run (a flight, a soak test) shows whether anything grows.
#include <cstdint>
#include <string>

namespace rgbdo {

struct ProcessResources {
  std::uint64_t frames = 0;  // output frames when taken
  double rss_mb = 0;
  int open_fds = 0;
  int threads = 0;
};

// Zeros where /proc cannot be read (not Linux, no /proc mounted).
ProcessResources process_resources(std::uint64_t frames);

// "after F frames RSS X MB, N fds, T threads"
std::string describe(const ProcessResources& r);

}  // namespace rgbdo
