#include "rgbd_odometry/app/calibration.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "rgbd_odometry/app/config_file.hpp"

namespace rgbdo {
namespace {

// A latency known as `offset` +- `standard_error`: its mean square, what the covariance's
// latency term takes as sigma^2 (the fit's uncertainty keeps a latency read as ~0 from being
// taken as exactly 0).
double rms_latency(double offset_s, double standard_error_s) { return std::hypot(offset_s, standard_error_s); }

}  // namespace

Calibration calibrate(const Config& run_config, const AccuracySummary& summary, const SensorEstimates& learnt) {
  Calibration c{run_config, {}, false};
  std::ostringstream notes;
  notes << std::setprecision(4);
  // Through the configuration's own table, which checks each key's range: a value outside
  // it is said and the key kept, so that the file always reads back.
  const auto set = [&](const char* key, double value) {
    try {
      if (set_config_value(c.config, key, value)) c.changed = true;
    } catch (const ConfigError& e) {
      notes << "# " << key << " kept: " << e.what() << "\n";
    }
  };
  notes << "# Calibrated against ground truth (rgbd-odometry --calibrate) over " << summary.evaluated
        << " pairs.\n";
  const TimeOffsetFit& colour = summary.rotation_time_offset;
  const TimeOffsetFit& depth = summary.depth_time_offset;
  if (colour.found) {
    const double sigma = rms_latency(colour.offset_s, colour.standard_error_s);
    notes << "# colour: frames taken " << colour.offset_s * 1e3 << " +- " << colour.standard_error_s * 1e3
          << " ms before their stamps (rotations over " << colour.pairs
          << " pairs): covariance.colour_latency_sigma_s = " << sigma << "\n";
    set("covariance.colour_latency_sigma_s", sigma);
  } else {
    notes << "# colour latency: not found within +-" << colour.max_offset_s * 1e3
          << " ms (too few pairs, or too little rotation): covariance.colour_latency_sigma_s kept\n";
  }
  if (colour.found && depth.found) {
    const double sigma = rms_latency(depth.offset_s - colour.offset_s,
                                     std::hypot(depth.standard_error_s, colour.standard_error_s));
    notes << "# depth: frames taken " << depth.offset_s * 1e3 << " +- " << depth.standard_error_s * 1e3
          << " ms before their stamps (tz over " << depth.pairs << " pairs): covariance.depth_latency_sigma_s = "
          << sigma << "\n";
    set("covariance.depth_latency_sigma_s", sigma);
  } else {
    notes << "# depth latency: not found: covariance.depth_latency_sigma_s kept\n";
  }
  if (learnt.depth_noise_coeff > 0) {
    notes << "# learnt from the data: depth noise " << learnt.depth_noise_coeff
          << " Z^2 (covariance.depth_noise_coeff), the depth alignment's sigma scaled by "
          << learnt.depth_sigma_scale_t << " / " << learnt.depth_sigma_scale_r
          << " (refinement.sigma_scale_prior = the larger)\n";
    set("covariance.depth_noise_coeff", learnt.depth_noise_coeff);
    set("refinement.sigma_scale_prior", std::max(learnt.depth_sigma_scale_t, learnt.depth_sigma_scale_r));
  } else {
    notes << "# depth noise and alignment trust: not learnt (refinement off): kept\n";
  }
  c.notes = notes.str();
  return c;
}

std::string calibration_yaml(const Calibration& calibration) {
  // config_yaml opens with the YAML directive and the document start, which stay first.
  const std::string body = config_yaml(calibration.config);
  const std::string opening = "%YAML:1.0\n---\n";
  if (body.rfind(opening, 0) == 0) return opening + calibration.notes + body.substr(opening.size());
  return calibration.notes + body;
}

}  // namespace rgbdo
