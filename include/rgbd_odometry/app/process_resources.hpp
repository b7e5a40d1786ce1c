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

// Resources after warm-up, about halfway and at the latest sample, taken on the output thread
// while every pipeline thread runs: a long run's summary shows whether memory, descriptors or
// threads grow. Memory settles in steps (buffers reaching their largest frame, the heap's
// top) in the first few thousand frames; a leak grows on: halfway to the end shows which.
// The halfway samples are taken at doubling frame counts, so one of the last two is between
// a quarter and a half of the run.
class ResourceSampler {
 public:
  void frame();  // one more output frame
  // "after W frames ...; after H frames ...; after N frames ...", or empty when the run was
  // too short for a sample after warm-up and one a period later.
  std::string summary() const;

 private:
  static constexpr std::uint64_t kWarmUpFrames = 200, kPeriod = 50;
  std::uint64_t frames_ = 0, next_doubling_ = 2 * kWarmUpFrames;
  std::optional<ProcessResources> warm_, latest_, previous_;  // previous: at least a period before the end
  std::optional<ProcessResources> doubling_, doubling_before_;
};

}  // namespace rgbdo
