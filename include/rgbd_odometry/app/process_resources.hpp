#pragma once
// What the running process holds, from Linux's /proc/self: resident memory, open file
// descriptors, threads. The summary compares a snapshot after warm-up with one at the end,
// so that a long run (a flight, a soak test) shows whether anything grows.
#include <cstdint>
#include <optional>
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

// Resources after warm-up, about halfway and near the end, taken on the output thread while
// every pipeline thread runs: a long run's summary shows whether memory, descriptors or
// threads grow. Each figure is a window of kWindowSamples samples, kPeriod frames apart:
// descriptors and threads from its first sample, memory the least of its samples. A single
// sample catches whatever buffers are in flight at that instant (a colour frame being decoded
// is 0.9 MB), so it wanders by a frame or two; a leak raises the least of every window.
// Memory settles in steps in the first few thousand frames (buffers reaching their largest
// frame, the heap's top); a leak grows on: halfway to the end shows which. The halfway
// windows start at doubling frame counts, so one of the last two is between a quarter and a
// half of the run.
class ResourceSampler {
 public:
  void frame();  // one more output frame
  // "after W frames ...; after H frames ...; after N frames ...", or empty when the run was
  // too short for two windows after warm-up.
  std::string summary() const;

  static constexpr std::uint64_t kWarmUpFrames = 200, kPeriod = 25, kWindowSamples = 8;
  static constexpr std::uint64_t kWindowFrames = kPeriod * kWindowSamples;

 private:
  std::uint64_t frames_ = 0, next_doubling_ = 2 * kWarmUpFrames;
  ProcessResources open_;  // the window being sampled
  std::uint64_t open_samples_ = 0;
  std::optional<ProcessResources> warm_, latest_, previous_;  // previous: the window before the latest
  std::optional<ProcessResources> doubling_, doubling_before_;
};

}  // namespace rgbdo
