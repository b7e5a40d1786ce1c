#include "rgbd_odometry/runtime/latency.hpp"

#include <algorithm>
#include <cmath>

namespace rgbdo {

void LatencyHistogram::add(double latency_ms) {
  if (!(latency_ms >= 0)) {  // NaN too
    ++ahead_;
    return;
  }
  const int bin = static_cast<int>(std::min(static_cast<double>(kBins - 1), latency_ms / kBinMs));
  ++bins_[static_cast<size_t>(bin)];
  ++count_;
  max_ms_ = std::max(max_ms_, latency_ms);
}

double LatencyHistogram::quantile_ms(double q) const {
  if (count_ == 0) return 0;
  // The smallest bin whose cumulative count reaches ceil(q * n): the nearest-rank quantile.
  const auto rank = static_cast<std::uint64_t>(std::max(1.0, std::ceil(q * static_cast<double>(count_))));
  std::uint64_t seen = 0;
  for (int b = 0; b < kBins; ++b) {
    seen += bins_[static_cast<size_t>(b)];
    // In the last bin (2 s and later) only the maximum is known: an upper bound, not a guess.
    if (seen >= rank) return b == kBins - 1 ? max_ms_ : std::min((b + 0.5) * kBinMs, max_ms_);
  }
  return max_ms_;
}

}  // namespace rgbdo
