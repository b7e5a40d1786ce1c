#pragma once
// The ground truth's own noise, estimated from the ground-truth file itself.
//
// Motion capture jitters from sample to sample (TUM: about 0.1-0.2 mm and 0.05-0.1 deg at
// 100 Hz). A frame-to-frame covariance of the same size, compared with such a reference,
// would measure the reference: the evaluation adds an allowance for it. Over a few samples
// the true motion is smooth, so each sample is compared with a quadratic in time fitted to
// its neighbours; the residual at the centre, divided by (1 - leverage), estimates the noise
// variance without bias, and the median over the file (scaled by chi2_1's median) keeps a few
// glitches from setting it.
#include <string>
#include <vector>

#include "rgbd_odometry/io/tum_sequence.hpp"

namespace rgbdo {

struct GroundTruthNoise {
  double position_m = 0;  // per sample and axis (standard deviation)
  double rotation_rad = 0;
  int samples = 0;        // samples with a full, gap-free neighbourhood
};

// half_window neighbours on each side; samples whose neighbourhood has a gap
// (groundtruth_gap_ns) are skipped.
GroundTruthNoise estimate_groundtruth_noise(const std::vector<StampedPose>& poses, int half_window = 3);

// What is added to the covariance of each compared motion, per axis (standard deviations).
struct GroundTruthAllowance {
  double translation_m = 0;
  double rotation_rad = 0;
  std::string origin;  // how it was obtained, printed with the result
};

// A relative motion differences two (interpolated) samples: sqrt(2) x the per-sample noise.
GroundTruthAllowance allowance_from(const GroundTruthNoise& noise);

// "auto" (estimated from the ground truth), "none", or "T_M,R_RAD" (e.g. "0.0003,0.0015").
// Throws std::invalid_argument naming the problem.
GroundTruthAllowance parse_allowance(const std::string& text, const GroundTruth& groundtruth);

}  // namespace rgbdo
