#pragma once
// Capture-to-output latency, summarised without storing every sample: a fixed histogram of
// 0.1 ms bins up to 2 s (allocated once), so hours of flight cost the same memory as a minute.
#include <array>
#include <cstdint>

namespace rgbdo {

class LatencyHistogram {
 public:
  static constexpr double kBinMs = 0.1;
  static constexpr int kBins = 20000;  // 2 s; anything later lands in the last bin (quantile: the max)

  // A negative latency (capture time ahead of the host clock) is not a latency but a fault of
  // the capture times (sensor/device_clock.hpp keeps them from running ahead). It is counted
  // apart, never binned as 0.
  void add(double latency_ms);
  std::uint64_t count() const { return count_; }  // latencies measured
  std::uint64_t ahead_of_clock() const { return ahead_; }
  double max_ms() const { return max_ms_; }
  // The q-quantile (0..1) to within one bin; 0 when empty.
  double quantile_ms(double q) const;

 private:
  std::array<std::uint32_t, kBins> bins_{};
  std::uint64_t count_ = 0, ahead_ = 0;
  double max_ms_ = 0;
};

}  // namespace rgbdo
