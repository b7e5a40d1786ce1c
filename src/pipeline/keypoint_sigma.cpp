#include "rgbd_odometry/pipeline/keypoint_sigma.hpp"

#include <algorithm>
#include <cmath>

namespace rgbdo {

namespace {
// The median of a Rayleigh distribution of scale s is s sqrt(2 ln 2); the scale of the
// difference of two keypoints' errors is sqrt(2) sigma.
const double kMedianPerSigma = std::sqrt(2.0 * std::log(2.0)) * std::sqrt(2.0);
}  // namespace

KeypointSigmaEstimate::KeypointSigmaEstimate(double pixel_sigma_px, double level_scale, int levels, int capacity)
    : levels_(std::clamp(levels, 1, kMaxLevels)) {
  const LearntConstantRule rule{.averaged_readings = 10,  // = 1 / kRate: where the two rules meet
                                .geometric = false,
                                .gain = kRate,
                                .max_step = kRate,
                                .min = kMinSigma_px,
                                .max = kMaxSigma_px};
  sigma_.reserve(static_cast<size_t>(levels_));
  for (int l = 0; l < levels_; ++l) {
    sigma_.emplace_back(pixel_sigma_px * std::pow(level_scale, l), rule);
    residuals_[static_cast<size_t>(l)].reserve(static_cast<size_t>(std::max(capacity, 0)));
  }
}

void KeypointSigmaEstimate::add(int level, double residual_px) {
  if (level < 0 || level >= levels_ || !std::isfinite(residual_px)) return;
  auto& r = residuals_[static_cast<size_t>(level)];
  if (r.size() < r.capacity()) r.push_back(static_cast<float>(residual_px));
}

void KeypointSigmaEstimate::update() {
  for (int l = 0; l < levels_; ++l) {
    auto& r = residuals_[static_cast<size_t>(l)];
    if (static_cast<int>(r.size()) >= kMinResiduals) {
      const auto mid = r.begin() + static_cast<std::ptrdiff_t>(r.size() / 2);
      std::nth_element(r.begin(), mid, r.end());
      sigma_[static_cast<size_t>(l)].add(static_cast<double>(*mid) / kMedianPerSigma);
    }
    r.clear();
  }
}

double KeypointSigmaEstimate::sigma_px(int level) const {
  return sigma_[static_cast<size_t>(std::clamp(level, 0, levels_ - 1))].value();
}

}  // namespace rgbdo
