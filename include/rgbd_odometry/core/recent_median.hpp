#pragma once
// The median of the last N values pushed: what a gate judging residuals by a fit's own scatter
// is bounded by, so that a calm start cannot turn every later, noisier value away (the fit
// would never learn the noise it refuses). Fixed storage, no allocation.
#include <algorithm>
#include <array>
#include <cstddef>

namespace rgbdo {

// chi-square(3)'s median: the median of 3-component squared residuals over it estimates their
// variance per component, the bound the gates take from a RecentMedian of them.
inline constexpr double kChi2_3_Median = 2.366;

template <std::size_t N>
class RecentMedian {
 public:
  void push(double v) {
    values_[next_] = v;
    next_ = (next_ + 1) % N;
    count_ = std::min(count_ + 1, N);
  }
  std::size_t count() const { return count_; }
  // Of the values held (the upper one of an even count's middle two); 0 when none.
  double median() const {
    if (count_ == 0) return 0;
    std::array<double, N> v{};
    std::copy_n(values_.begin(), count_, v.begin());
    const auto mid = v.begin() + static_cast<std::ptrdiff_t>(count_ / 2);
    std::nth_element(v.begin(), mid, v.begin() + static_cast<std::ptrdiff_t>(count_));
    return *mid;
  }

 private:
  std::array<double, N> values_{};
  std::size_t next_ = 0, count_ = 0;
};

}  // namespace rgbdo
