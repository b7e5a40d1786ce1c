#pragma once
// A sensor constant learnt from one noisy reading a pair, started at a configured prior: the
// rule the depth noise (DepthNoiseEstimate) and each pyramid level's keypoint localisation
// (KeypointSigmaEstimate) share.
//
//  - Warm-up: the first `averaged_readings` readings are averaged with the prior, the prior
//    counted as one reading. A sensor far from the prior (ICL-NUIM's depth noise lies 24x
//    below the Kinect's, the Kinect's fine keypoints at twice the corner-quantisation law)
//    gets there in a few pairs instead of creeping at the rate below, during which every
//    weight built on the constant would be wrong. `geometric` averages in log space, for a
//    constant that may lie decades from its prior.
//  - After it each reading moves the value by `gain` of the difference, and by at most
//    `max_step` of the value itself: one wild pair (a blurred frame, a bare wall) cannot swing
//    it, and a real change is followed within a few dozen pairs.
//  - The value stays within [min, max], so no weight built on it is ever zero or infinite.
// Non-finite or negative readings say nothing and are not counted.
#include <algorithm>
#include <cmath>

namespace rgbdo {

// Every user sets every field (designated initialisers); `geometric` needs min > 0.
struct LearntConstantRule {
  int averaged_readings = 10;
  bool geometric = false;
  double gain = 1;      // share of (reading - value) taken per reading after the warm-up
  double max_step = 0.1;  // the most one reading moves the value, relative to it
  double min = 0, max = 1;
};

class LearntConstant {
 public:
  LearntConstant(double prior, const LearntConstantRule& rule)
      : rule_(rule), value_(std::clamp(prior, rule.min, rule.max)) {}

  void add(double reading) {
    if (!(reading >= 0) || !std::isfinite(reading)) return;
    double next;
    if (readings_ < rule_.averaged_readings) {
      // A reading beyond the bounds enters the mean at the bound (an exact depth's 0 has no log).
      ++readings_;
      const double share = 1.0 / (readings_ + 1);  // the prior and the readings so far, equally
      const double r = std::clamp(reading, rule_.min, rule_.max);
      next = rule_.geometric ? value_ * std::pow(r / value_, share) : value_ + share * (r - value_);
    } else {
      const double bound = rule_.max_step * value_;
      next = value_ + std::clamp(rule_.gain * (reading - value_), -bound, bound);
    }
    value_ = std::clamp(next, rule_.min, rule_.max);
  }

  double value() const { return value_; }

 private:
  LearntConstantRule rule_;
  double value_;
  int readings_ = 0;
};

}  // namespace rgbdo
