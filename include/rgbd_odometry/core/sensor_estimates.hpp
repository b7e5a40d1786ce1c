#pragma once
// The sensor's constants as the pipeline learns them online, carried with each pair result
// to the summary and the live status line.
#include <string>

namespace rgbdo {

// The sensor's constants learnt online from the data, without ground truth
// (pipeline/depth_alignment.hpp, pipeline/keypoint_sigma.hpp); all 0 while the depth alignment is off.
struct SensorEstimates {
  // The factors the depth alignment's own sigma is scaled by, translation and rotation (AlignmentTrust).
  double depth_sigma_scale_t = 0, depth_sigma_scale_r = 0;
  double depth_lag_s = 0;        // the depth's capture lag behind the colour (DepthLagEstimate)
  double depth_noise_coeff = 0;  // sigma_Z = c Z^2, 1/m (DepthNoiseEstimate)
  // The keypoints' localisation at the finest and the coarsest level (KeypointSigmaEstimate).
  double keypoint_sigma_fine_px = 0, keypoint_sigma_coarse_px = 0;
  int coarse_level = 0;
};

// In a few words, for the summary and the status line.
std::string sensor_estimates_text(const SensorEstimates& e);

}  // namespace rgbdo
