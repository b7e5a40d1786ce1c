#include "rgbd_odometry/core/sensor_estimates.hpp"

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

}  // namespace rgbdo
