#include "rgbd_odometry/core/sensor_estimates.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace rgbdo {

std::string sensor_estimates_text(const SensorEstimates& e) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(3) << "depth noise " << e.depth_noise_coeff * 1e3 << "e-3 Z^2"
    << std::setprecision(1) << ", depth " << e.depth_lag_s * 1e3 << " ms behind the colour" << std::setprecision(2)
    << ", keypoints within " << e.keypoint_sigma_fine_px << " px (level 0) to " << e.keypoint_sigma_coarse_px
    << " px (level " << e.coarse_level << ")";
  return s.str();
}

std::string capture_latency_text(const CaptureTiming& t) {
  if (!t.gyro) return {};
  std::ostringstream s;
  s << std::fixed << std::setprecision(1);
  if (t.known) {
    s << "capture latency " << t.latency_s * 1e3 << " +- " << t.sigma_s * 1e3 << " ms against the gyro, axes "
      << t.axis_spread_s * 1e3 << " ms apart";
    if (t.depth_known)
      s << ", depth " << t.depth_latency_s * 1e3 << " +- " << t.depth_sigma_s * 1e3 << " ms behind its stamps";
  } else {
    s << "capture latency not measured yet against the gyro";
  }
  s << " (applied " << t.applied_s * 1e3 << " ms; " << t.pairs << " pairs, " << t.uncovered << " not covered by the gyro, "
    << t.rejected << " left out as failed fits, " << t.at_rest << " at rest)";
  if (t.colour_image_known)
    s << "; the colour image's own latency " << t.colour_image_latency_s * 1e3 << " +- " << t.colour_image_sigma_s * 1e3
      << " ms, its image shift moved " << t.image_shift_retime_s * 1e3 << " ms";
  return s.str();
}

std::string mount_text(const CaptureTiming& t, double configured_roll_deg, double configured_pitch_deg,
                       double configured_yaw_deg, double warning_deg) {
  if (!t.mount_known) return {};
  // The angles' differences, wrapped to (-180, 180].
  const auto apart = [](double a, double b) { return std::abs(std::remainder(a - b, 360.0)); };
  const double worst = std::max({apart(t.mount_roll_deg, configured_roll_deg), apart(t.mount_pitch_deg, configured_pitch_deg),
                                 apart(t.mount_yaw_deg, configured_yaw_deg)});
  std::ostringstream s;
  s << std::fixed << std::setprecision(1);
  if (worst > warning_deg) s << "WARNING: ";
  s << "mount measured against the autopilot's gyro: roll " << t.mount_roll_deg << " pitch " << t.mount_pitch_deg
    << " yaw " << t.mount_yaw_deg << " deg (configured body.camera_roll_deg " << configured_roll_deg << ", _pitch_deg "
    << configured_pitch_deg << ", _yaw_deg " << configured_yaw_deg << "; " << t.mount_pairs << " pairs)";
  if (worst > warning_deg)
    s << ": " << worst << " deg apart, over " << warning_deg
      << ": check the camera's mounting and body.*, or the autopilot's board orientation";
  return s.str();
}

}  // namespace rgbdo
