#pragma once
// The sensor's constants as the pipeline learns them online, carried with each pair result
// to the summary and the live status line.
#include <cstdint>
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

// When the frames were taken, as measured against the autopilot's gyro
// (pipeline/capture_latency.hpp), and the camera's mount the same pairs show.
struct CaptureTiming {
  bool gyro = false;       // gyro samples are read (live: the autopilot's ATTITUDE; replay: imu.txt)
  bool known = false;      // the latency is measured
  double latency_s = 0;    // stamp minus capture instant, on the gyro's clock
  double sigma_s = 0;      // its standard error
  double axis_spread_s = 0;  // the rotation axes' own latencies about it (pipeline/capture_latency.hpp)
  double applied_s = 0;    // what this pair's current frame was restamped by
  bool depth_known = false;   // the depth alignment's rotations' latency, behind the depth stamps
  double depth_latency_s = 0, depth_sigma_s = 0;
  // The colour image's own latency, 2 L - L_d (CaptureClock::colour_image_latency_s), and how far
  // the pairs' image shift was moved to their times (0: not moved).
  bool colour_image_known = false;
  double colour_image_latency_s = 0, colour_image_sigma_s = 0;
  double image_shift_retime_s = 0;
  std::uint64_t pairs = 0; // pairs measured against the gyro so far
  std::uint64_t uncovered = 0, rejected = 0, at_rest = 0;  // of those: no gyro over them, a failed fit's, at rest
  bool mount_known = false;
  double mount_roll_deg = 0, mount_pitch_deg = 0, mount_yaw_deg = 0;
  int mount_pairs = 0;
};

// "capture latency 16.4 +- 0.9 ms against the gyro, axes 4.7 ms apart (applied 16.4 ms; 233
// pairs)"; empty without a gyro.
std::string capture_latency_text(const CaptureTiming& t);
// "mount measured against the autopilot's gyro: roll R pitch P yaw Y deg (configured: ...)",
// "WARNING: ..." when an angle differs by more than warning_deg; empty when not measured.
std::string mount_text(const CaptureTiming& t, double configured_roll_deg, double configured_pitch_deg,
                       double configured_yaw_deg, double warning_deg);

}  // namespace rgbdo
