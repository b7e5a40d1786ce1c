#include "rgbd_odometry/app/process_resources.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <system_error>

namespace rgbdo {

ProcessResources process_resources(std::uint64_t frames) {
  ProcessResources r;
  r.frames = frames;
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);) {
    std::istringstream fields(line);
    std::string key;
    fields >> key;
    if (key == "VmRSS:") {
      double kb = 0;
      fields >> kb;
      r.rss_mb = kb / 1024.0;
    } else if (key == "Threads:") {
      fields >> r.threads;
    }
  }
  std::error_code ec;
  for (std::filesystem::directory_iterator it("/proc/self/fd", ec), end; !ec && it != end; it.increment(ec))
    ++r.open_fds;
  if (r.open_fds > 0) --r.open_fds;  // the directory iterator's own descriptor
  return r;
}

std::string describe(const ProcessResources& r) {
  std::ostringstream s;
  s << "after " << r.frames << " frames RSS " << std::fixed << std::setprecision(1) << r.rss_mb << " MB, "
    << r.open_fds << " fds, " << r.threads << " threads";
  return s.str();
}

void ResourceSampler::frame() {
  ++frames_;
  if (frames_ < kWarmUpFrames || (frames_ - kWarmUpFrames) % kPeriod != 0) return;
  const ProcessResources sample = process_resources(frames_);
  if (open_samples_ == 0) {
    open_ = sample;
  } else {
    open_.rss_mb = std::min(open_.rss_mb, sample.rss_mb);
  }
  if (++open_samples_ < kWindowSamples) return;
  open_samples_ = 0;
  if (!warm_) {
    warm_ = open_;
    return;
  }
  previous_ = latest_;  // the latest window may close while the source's threads wind down
  latest_ = open_;
  if (open_.frames >= next_doubling_) {
    doubling_before_ = doubling_;
    doubling_ = open_;
    while (next_doubling_ <= open_.frames) next_doubling_ *= 2;
  }
}

std::string ResourceSampler::summary() const {
  if (!warm_ || !previous_) return "";
  const auto& halfway = doubling_ && doubling_->frames * 2 <= previous_->frames ? doubling_ : doubling_before_;
  std::string s = describe(*warm_) + "; ";
  if (halfway && halfway->frames > warm_->frames && halfway->frames < previous_->frames) s += describe(*halfway) + "; ";
  return s + describe(*previous_);
}

}  // namespace rgbdo
