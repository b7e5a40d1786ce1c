#include "rgbd_odometry/core/config.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <span>
#include <sstream>
#include <variant>

namespace rgbdo {
namespace {

// One settable parameter: where it lives in Config and the range it must lie in.
struct Param {
  std::string key;  // "section.name"
  std::string_view unit;  // empty: none
  std::string_view help;  // one line: what it does, what its special values mean
  std::variant<int*, double*, bool*, std::string*, std::uint64_t*> target;
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  // Where zero is singular (a variance, a weight), min itself is refused: (min, max].
  bool above_min = false;
};

std::vector<Param> param_table(Config& c) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  return {
      {"camera.width", "px", "image width the intrinsics are for; frames of another size are refused", &c.camera.width, 16, 8192},
      {"camera.height", "px", "image height the intrinsics are for", &c.camera.height, 16, 8192},
      {"camera.fx", "px", "focal length along x (calibrated; or camera.calibration_file)", &c.camera.fx, 1, 1e5},
      {"camera.fy", "px", "focal length along y", &c.camera.fy, 1, 1e5},
      {"camera.cx", "px", "principal point x", &c.camera.cx, 0, 8192},
      {"camera.cy", "px", "principal point y", &c.camera.cy, 0, 8192},
      {"camera.k1", "", "radial distortion k1 (OpenCV order; in a file also camera.distortion: [k1, k2, p1, p2, k3])", &c.camera.distortion[0], -100, 100},
      {"camera.k2", "", "radial distortion k2", &c.camera.distortion[1], -100, 100},
      {"camera.p1", "", "tangential distortion p1", &c.camera.distortion[2], -1, 1},
      {"camera.p2", "", "tangential distortion p2", &c.camera.distortion[3], -1, 1},
      {"camera.k3", "", "radial distortion k3", &c.camera.distortion[4], -100, 100},
      {"depth.units_per_m", "1/m", "raw uint16 depth value per metre (TUM 5000, OpenNI2 1 mm: 1000)", &c.depth.units_per_m, 1e-3, 1e6},
      {"depth.min_m", "m", "nearer depth is invalid (PrimeSense: nothing reliable below ~0.4 m)", &c.depth.min_m, 0.0, 100},
      {"depth.max_m", "m", "farther depth is invalid (beyond ~4.5 m sigma_Z exceeds 3 cm)", &c.depth.max_m, 0.01, 100},
      {"depth.edge_max_relative_step", "", "a keypoint whose 5x5 depth neighbourhood spans more than this fraction of its depth is on an occlusion edge: not used", &c.depth.edge_max_relative_step, 0.0, inf},
      {"depth.compensate_timing", "", "carry each keypoint's depth from the depth frame's capture time to the colour frame's", &c.depth.compensate_timing},
      {"depth.registration_x_px", "px", "the depth image's misregistration against the colour along x: what the colour shows at u is in the depth at u - this (bench/depth_lag_edges.py measures it)", &c.depth.registration_x_px, -50, 50},
      {"depth.registration_y_px", "px", "the same along y", &c.depth.registration_y_px, -50, 50},
      {"features.detector", "", "GRID_ORB (ours) or an OpenCV detector by name: ORB, AKAZE, BRISK, SIFT, KAZE, FAST, GFTT, AGAST", &c.features.detector},
      {"features.descriptor", "", "GRID_ORB (with its detector) or an OpenCV descriptor: ORB, AKAZE, BRISK, SIFT, KAZE", &c.features.descriptor},
      {"features.max_features", "", "keypoints per frame", &c.features.max_features, 10, 100000},
      {"features.border_px", "px", "image periphery masked before detection (distortion is worst there)", &c.features.border_px, 0, 1000},
      {"features.orb_levels", "", "scale-pyramid levels", &c.features.orb_levels, 1, 16},
      {"features.orb_scale_factor", "", "scale between pyramid levels", &c.features.orb_scale_factor, 1.01, 2.0},
      {"features.fast_threshold", "", "FAST corner threshold (grey levels)", &c.features.fast_threshold, 1, 255},
      {"matching.ratio", "", "symmetric ratio test: best / second-best distance below this", &c.matching.ratio, 1e-6, 1.0},
      {"matching.window_px", "px", "half width of the search window around the motion prior's prediction; 0: every pair, as the paper", &c.matching.window_px, 0, 1e5},
      {"matching.subpixel_tracking", "", "move each matched keypoint to where the previous keypoint's patch lies, below a pixel; off: integer corners, as the paper", &c.matching.subpixel_tracking},
      {"ransac.inlier_threshold_m", "m", "lambda_inlier: 3-D distance of an inlier", &c.ransac.inlier_threshold_m, 1e-5, 10},
      {"ransac.max_iterations", "", "RANSAC hypotheses at most", &c.ransac.max_iterations, 1, 1000000},
      {"ransac.refine_threshold", "", "refit with the threshold min(3 sigma_inliers, lambda_inlier)", &c.ransac.refine_threshold},
      {"ransac.min_inliers", "", "fewer inliers and the pair is reported failed", &c.ransac.min_inliers, 3, 1000000},
      {"ransac.adaptive_stop", "", "stop once an all-inlier sample was drawn with 99.9 % probability", &c.ransac.adaptive_stop},
      {"covariance.perturbations", "", "perturbed refits the 6x6 covariance is estimated from", &c.covariance.perturbations, 8, 100000},
      {"covariance.model", "", "physical (core/noise_model.hpp) or paper (Willis & Brink eq. 2 alone)", &c.covariance.model},
      {"covariance.depth_noise_coeff", "1/m", "axial depth noise sigma_Z = coeff Z^2", &c.covariance.depth_noise_coeff, 1e-9, 1.0},
      {"covariance.depth_lateral_sigma_px", "px", "lateral noise of the depth map", &c.covariance.depth_lateral_sigma_px, 0.0, 100},
      {"covariance.timing_sigma_s", "s", "colour-to-depth capture-time offset error; < 0: estimated from the stamps' jitter", &c.covariance.timing_sigma_s, -1, 1},
      {"covariance.resample_cell_px", "px", "each perturbation resamples the inliers by image cells this size; 0: none", &c.covariance.resample_cell_px, 0, 1e5},
      {"covariance.colour_latency_sigma_s", "s", "colour capture latency behind its stamps the stamps do not show; 0: calibrated away", &c.covariance.colour_latency_sigma_s, 0, 1},
      {"covariance.depth_latency_sigma_s", "s", "depth capture latency behind the colour; 0: calibrated away", &c.covariance.depth_latency_sigma_s, 0, 1},
      {"covariance.integration_window_s", "s", "a consumer summing motions over this horizon stays covered against the latencies; 0: per pair only", &c.covariance.integration_window_s, 0, 3600},
      {"covariance.pixel_sigma_px", "px", "keypoint localisation error at full resolution (integer corners: 1/sqrt(12))", &c.covariance.pixel_sigma_px, 0.0, 100, true},  // 0: singular fit weights
      {"covariance.residual_variance_factor", "", "scale the noise by the fit's a-posteriori variance factor", &c.covariance.residual_variance_factor},
      {"covariance.scale", "", "multiplies the reported covariance; 1: the noise model as it stands", &c.covariance.scale, 1e-6, 1e6},
      {"refinement.enabled", "", "refine the feature motion by aligning the two depth maps and fuse the two by information", &c.refinement.enabled},
      {"refinement.stride_px", "px", "the depth maps are sampled every this many pixels for the alignment", &c.refinement.stride_px, 2, 64},
      {"refinement.iterations", "", "Gauss-Newton steps of the depth alignment at most", &c.refinement.iterations, 1, 100},
      {"refinement.max_distance_m", "m", "a depth point further than this from its associated point is not used", &c.refinement.max_distance_m, 1e-4, 10, true},
      {"refinement.min_points", "", "fewer associated depth points and the feature motion stands alone", &c.refinement.min_points, 10, 1000000},
      {"refinement.cell_px", "px", "image cells whose residuals may be correlated: the alignment covariance's clusters", &c.refinement.cell_px, 8, 1e5},
      {"refinement.sigma_scale_prior", "", "the depth alignment's sigma is scaled by factors learnt against the features; their start", &c.refinement.sigma_scale_prior, 1, 1e6},
      {"refinement.sigma_scale_rate", "", "how far one pair may move those factors (share per pair)", &c.refinement.sigma_scale_rate, 0, 0.5},
      {"refinement.sigma_scale_max", "", "the factors' ceiling: beyond it the sensor's depth adds nothing", &c.refinement.sigma_scale_max, 1, 1e9},
      {"refinement.max_sigma_scale_fused", "", "the alignment is fused only while both learnt factors are at most this: beyond, its errors are ones its residuals cannot see", &c.refinement.max_sigma_scale_fused, 1, 1e9},
      {"refinement.max_depth_lag_s", "s", "the depth's capture lag behind the colour, learnt from the depth alignment against the features and reported, at most this much", &c.refinement.max_depth_lag_s, 0, 1},
      {"refinement.max_depth_lag_fused_s", "s", "the alignment is fused only while the depth's learnt lag behind the colour is at most this either way: a depth taken at another instant measures another motion", &c.refinement.max_depth_lag_fused_s, 0, 1},
      {"refinement.distrusted_sigma_scale", "", "where the learnt factors or lag refuse fusion, the alignment is fused with its sigma in sideways translation scaled by this fixed factor instead; 0: the features stand alone", &c.refinement.distrusted_sigma_scale, 0, 1e6},
      {"refinement.distrusted_sigma_scale_optical_axis", "", "the same for its translation along the optical axis, which the depth's lag and distortion move most", &c.refinement.distrusted_sigma_scale_optical_axis, 1, 1e6},
      {"refinement.distrusted_sigma_scale_rotation", "", "the same for its rotation", &c.refinement.distrusted_sigma_scale_rotation, 1, 1e6},
      {"latency.enabled", "", "measure when the frames were taken against the autopilot's gyro (live: its ATTITUDE; replay: imu.txt or --imu) and stamp every motion then", &c.latency.enabled},
      {"latency.min_s", "s", "the latencies searched (stamp minus capture instant, on the gyro's clock): from", &c.latency.min_s, -1, 1},
      {"latency.max_s", "s", "to", &c.latency.max_s, -1, 1},
      {"latency.memory_s", "s", "a moving camera's evidence fades over this long, so a slowly changing latency is followed; at rest nothing fades", &c.latency.memory_s, 1, 1e6},
      {"latency.converged_sigma_s", "s", "applied once known to this standard error", &c.latency.converged_sigma_s, 1e-5, 1, true},
      {"latency.max_slew", "s/s", "the applied latency moves towards the estimate at most this fast (seconds per second of frames)", &c.latency.max_slew, 1e-4, 0.5},
      {"latency.mount_warning_deg", "deg", "a camera mount measured against the gyro further than this from body.* is warned about", &c.latency.mount_warning_deg, 0.1, 180},
      {"sensor.fps", "Hz", "live sensor frame rate", &c.sensor.fps, 1, 120},
      {"sensor.registration", "", "hardware depth-to-colour registration", &c.sensor.registration},
      {"sensor.frame_timeout_ms", "ms", "no frame this long: the sensor is reported lost", &c.sensor.frame_timeout_ms, 100, 600000},
      {"sensor.pairing_wait_ms", "ms", "how long a colour frame waits for a depth frame after it", &c.sensor.pairing_wait_ms, 0, 10000},
      {"sensor.reconnect_timeout_s", "s", "after a loss, re-open for this long; < 0: for ever (the vehicle), 0: stop at the first loss", &c.sensor.reconnect_timeout_s, -1, 1e9},
      {"sensor.reconnect_interval_ms", "ms", "time between re-open attempts", &c.sensor.reconnect_interval_ms, 10, 600000},
      {"sensor.record_oni", "", "non-empty: also record the sensor's streams to this .oni file", &c.sensor.record_oni},
      {"runtime.processing_threads", "", "1: extraction and estimation in one thread; 2: overlapped", &c.runtime.processing_threads, 1, 2},
      {"runtime.extraction_threads", "", "threads extracting one frame (the same result on any number)", &c.runtime.extraction_threads, 1, 8},
      {"runtime.cpu_affinity", "", "CPUs for capture, extraction, estimation, output (wrapping), e.g. \"4,5,6,7\"; empty: none", &c.runtime.cpu_affinity},
      {"log.max_total_mb", "MB", "the odometry log and trajectory of this and earlier runs together; the oldest go first", &c.log.max_total_mb, 0.01, 1e7},
      {"body.camera_roll_deg", "deg", "camera mount roll from forward-looking (Z-Y-X)", &c.body.camera_roll_deg, -180, 180},
      {"body.camera_pitch_deg", "deg", "camera mount pitch from forward-looking; -90 looks down", &c.body.camera_pitch_deg, -90, 90},
      {"body.camera_yaw_deg", "deg", "camera mount yaw from forward-looking", &c.body.camera_yaw_deg, -180, 180},
      {"body.camera_x_m", "m", "camera position in the FRD body frame, forward", &c.body.camera_x_m, -10, 10},
      {"body.camera_y_m", "m", "camera position, right", &c.body.camera_y_m, -10, 10},
      {"body.camera_z_m", "m", "camera position, down", &c.body.camera_z_m, -10, 10},
      {"link.uri", "", "udp://HOST:PORT, udpin://[ADDR]:PORT or serial:///dev/ttyX[:BAUD]; empty: no link", &c.link.uri},
      {"link.system_id", "", "our MAVLink system id: the vehicle's", &c.link.system_id, 1, 255},
      {"link.odometry", "", "send ODOMETRY (PX4 EKF2, ArduPilot EKF3)", &c.link.odometry},
      {"link.vision_position_delta", "", "send VISION_POSITION_DELTA instead (ArduPilot; needs link.odometry false)", &c.link.vision_position_delta},
      {"link.quality_sigma_fail_m", "m", "pair sigma_t at which ODOMETRY quality reaches 1 %", &c.link.quality_sigma_fail_m, 1e-4, 10},
      {"link.velocity_error_min_mps", "m/s", "ArduPilot EK3_VIS_VERR_MIN: confidence maps onto [min, max]", &c.link.velocity_error_min_mps, 0.0, 100, true},  // 0: an exact velocity to the EKF
      {"link.velocity_error_max_mps", "m/s", "ArduPilot EK3_VIS_VERR_MAX", &c.link.velocity_error_max_mps, 0.0, 100},
      {"link.autopilot_system_id", "", "follow only this system's autopilot; 0: the first heard", &c.link.autopilot_system_id, 0, 255},
      {"link.autopilot_timeout_s", "s", "nothing heard this long: the autopilot is reported gone", &c.link.autopilot_timeout_s, 0.2, 60},
      {"link.timesync_rate_hz", "Hz", "our TIMESYNC requests while an autopilot is up; 0: none", &c.link.timesync_rate_hz, 0.0, 20},
      {"link.timesync_max_rtt_ms", "ms", "slower answers are not used for our clock offset", &c.link.timesync_max_rtt_ms, 0.1, 10000},
      {"link.ekf_origin", "deg, deg, m", "LATITUDE, LONGITUDE, ALTITUDE (AMSL) sent as SET_GPS_GLOBAL_ORIGIN and SET_HOME_POSITION (ArduPilot needs it without GPS); empty: none", &c.link.ekf_origin},
      {"link.attitude_rate_hz", "Hz", "the autopilot's ATTITUDE (its gyro rates, for latency.*) asked for at this rate; 0: not asked", &c.link.attitude_rate_hz, 0.0, 500},
      {"link.delta_min_interval_ms", "ms", "VISION_POSITION_DELTA composed over at least this (ArduPilot drops closer ones: 50)", &c.link.delta_min_interval_ms, 0.0, 1000},
      {"seed", "", "seeds RANSAC and the perturbations with each pair's content: the same frames, the same result", &c.seed, 0, 2147483647},  // a file's integers are 32-bit (OpenCV's reader)
  };
}

Param* find_param(std::vector<Param>& table, const std::string& key) {
  for (auto& p : table)
    if (p.key == key) return &p;
  return nullptr;
}

double parse_number(const std::string& key, const std::string& text) {
  double value = 0;
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc() || ptr != end || !std::isfinite(value))
    throw ConfigError("config key '" + key + "': expected a number, got '" + text + "'");
  return value;
}

void check_range(const Param& p, double value) {
  if (p.above_min && !(value > p.min && value <= p.max)) {
    std::ostringstream msg;
    msg << "config key '" << p.key << "': value " << value << " is outside (" << p.min << ", " << p.max
        << "]: it must be above " << p.min << " (at " << p.min << " the estimate is singular)";
    throw ConfigError(msg.str());
  }
  if (!(value >= p.min && value <= p.max)) {
    std::ostringstream msg;
    msg << "config key '" << p.key << "': value " << value << " is outside [" << p.min << ", "
        << p.max << "]";
    throw ConfigError(msg.str());
  }
}

void check_integral(const Param& p, double value) {
  if (value != std::floor(value))
    throw ConfigError("config key '" + p.key + "': expected a whole number, got " +
                      std::to_string(value));
}

// Sets a parameter from its text form (command line) after checking type and range.
void set_from_text(Param& p, const std::string& text) {
  std::visit(
      [&](auto* target) {
        using T = std::remove_pointer_t<decltype(target)>;
        if constexpr (std::is_same_v<T, std::string>) {
          *target = text;
        } else if constexpr (std::is_same_v<T, bool>) {
          if (text == "true" || text == "1" || text == "on") *target = true;
          else if (text == "false" || text == "0" || text == "off") *target = false;
          else throw ConfigError("config key '" + p.key + "': expected true/false, got '" + text + "'");
        } else {
          const double v = parse_number(p.key, text);
          check_range(p, v);
          if constexpr (!std::is_same_v<T, double>) check_integral(p, v);
          *target = static_cast<T>(v);
        }
      },
      p.target);
}

bool listed(std::span<const std::string_view> names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

std::string joined(std::span<const std::string_view> names) {
  std::string text;
  for (const auto name : names) text += (text.empty() ? "" : ", ") + std::string(name);
  return text;
}

}  // namespace

bool set_config_value(Config& config, const std::string& key, const ConfigValue& value) {
  auto table = param_table(config);
  Param* p = find_param(table, key);
  if (!p) return false;
  std::visit(
      [&](auto* target) {
        using T = std::remove_pointer_t<decltype(target)>;
        if constexpr (std::is_same_v<T, std::string>) {
          if (!std::holds_alternative<std::string>(value))
            throw ConfigError("config key '" + p->key + "': expected a string");
          *target = std::get<std::string>(value);
        } else if constexpr (std::is_same_v<T, bool>) {
          if (const auto* text = std::get_if<std::string>(&value)) {
            set_from_text(*p, *text);
          } else {
            const double v = std::get<double>(value);
            if (v != std::floor(v)) throw ConfigError("config key '" + p->key + "': expected true/false");
            set_from_text(*p, std::to_string(static_cast<long long>(v)));
          }
        } else {
          if (!std::holds_alternative<double>(value))
            throw ConfigError("config key '" + p->key + "': expected a number");
          const double v = std::get<double>(value);
          check_range(*p, v);
          if constexpr (!std::is_same_v<T, double>) check_integral(*p, v);
          *target = static_cast<T>(v);
        }
      },
      p->target);
  return true;
}

void apply_overrides(Config& config, const std::vector<std::string>& assignments) {
  auto table = param_table(config);
  for (const auto& a : assignments) {
    const auto eq = a.find('=');
    if (eq == std::string::npos)
      throw ConfigError("override '" + a + "': expected KEY=VALUE (for example ransac.max_iterations=300)");
    const std::string key = a.substr(0, eq);
    Param* p = find_param(table, key);
    if (!p) throw ConfigError("override '" + a + "': unknown key '" + key + "'");
    set_from_text(*p, a.substr(eq + 1));
  }
}

std::vector<std::string> config_keys() {
  Config c;
  std::vector<std::string> keys;
  for (const auto& p : param_table(c)) keys.push_back(p.key);
  return keys;
}

namespace {

std::string shortest(double v) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char text[32];
  const auto [end, ec] = std::to_chars(text, text + sizeof text, v);  // the shortest that reads back exactly
  return ec == std::errc() ? std::string(text, end) : std::to_string(v);
}

}  // namespace

std::vector<ConfigKeyInfo> describe_config(const Config& config) {
  Config copy = config;
  std::vector<ConfigKeyInfo> out;
  for (const Param& p : param_table(copy)) {
    ConfigKeyInfo info;
    info.key = p.key;
    info.unit = std::string(p.unit);
    info.help = std::string(p.help);
    std::visit(
        [&](auto* target) {
          using T = std::remove_pointer_t<decltype(target)>;
          if constexpr (std::is_same_v<T, std::string>) {
            info.kind = ConfigKeyInfo::Kind::Text;
            info.value = *target;
          } else if constexpr (std::is_same_v<T, bool>) {
            info.kind = ConfigKeyInfo::Kind::Boolean;
            info.value = *target ? "true" : "false";
          } else {
            info.kind = std::is_same_v<T, double> ? ConfigKeyInfo::Kind::Number : ConfigKeyInfo::Kind::Integer;
            info.value = std::is_same_v<T, double> ? shortest(static_cast<double>(*target)) : std::to_string(*target);
            info.range = std::string(p.above_min ? "(" : "[") + shortest(p.min) + ", " + shortest(p.max) + "]";
          }
        },
        p.target);
    out.push_back(std::move(info));
  }
  return out;
}

void validate(const Config& config) {
  Config copy = config;
  for (auto& p : param_table(copy)) {
    std::visit(
        [&](auto* target) {
          using T = std::remove_pointer_t<decltype(target)>;
          if constexpr (!std::is_same_v<T, std::string> && !std::is_same_v<T, bool>)
            check_range(p, static_cast<double>(*target));
        },
        p.target);
  }
  const auto& c = config;
  if (c.depth.min_m >= c.depth.max_m)
    throw ConfigError("config key 'depth.min_m': must be below depth.max_m");
  if (c.camera.cx >= c.camera.width || c.camera.cy >= c.camera.height)
    throw ConfigError("config key 'camera.cx': principal point lies outside the image");
  if (2 * c.features.border_px >= std::min(c.camera.width, c.camera.height))
    throw ConfigError("config key 'features.border_px': the border leaves no image");
  if (!listed(kCovarianceModels, c.covariance.model))
    throw ConfigError("config key 'covariance.model': unknown model '" + c.covariance.model + "' (" +
                      joined(kCovarianceModels) + ")");
  if (!listed(kFeatureDetectors, c.features.detector))
    throw ConfigError("config key 'features.detector': unknown detector '" + c.features.detector + "' (" +
                      joined(kFeatureDetectors) + ")");
  if (!listed(kFeatureDescriptors, c.features.descriptor))
    throw ConfigError("config key 'features.descriptor': unknown descriptor '" + c.features.descriptor + "' (" +
                      joined(kFeatureDescriptors) + ")");
  if ((c.features.descriptor == kGridOrb) != (c.features.detector == kGridOrb))
    throw ConfigError("config key 'features.descriptor': GRID_ORB is a detector and descriptor in one: set both");
  if ((c.features.descriptor == "AKAZE") != (c.features.detector == "AKAZE") ||
      (c.features.descriptor == "KAZE") != (c.features.detector == "KAZE"))
    throw ConfigError("config key 'features.descriptor': " + c.features.descriptor +
                      " descriptors need the matching (A)KAZE detector");
  if (c.refinement.stride_px * 4 > std::min(c.camera.width, c.camera.height))
    throw ConfigError("config key 'refinement.stride_px': fewer than 4 grid rows in the image");
  if (c.ransac.min_inliers < 3)
    throw ConfigError("config key 'ransac.min_inliers': a rigid motion needs at least 3");
  if (c.latency.max_s - c.latency.min_s < 0.01)
    throw ConfigError("config key 'latency.max_s': must be at least 10 ms above latency.min_s");
  (void)parse_cpu_list(c.runtime.cpu_affinity);
  if (c.link.velocity_error_min_mps >= c.link.velocity_error_max_mps)
    throw ConfigError("config key 'link.velocity_error_min_mps': must be below link.velocity_error_max_mps");
  if (!c.link.uri.empty() && !c.link.odometry && !c.link.vision_position_delta)
    throw ConfigError("config key 'link.odometry': a link with neither ODOMETRY nor VISION_POSITION_DELTA sends nothing");
  if (c.link.odometry && c.link.vision_position_delta)
    throw ConfigError(
        "config key 'link.vision_position_delta': with link.odometry also on, ArduPilot's EKF3 would fuse the same "
        "motion twice (ODOMETRY as external navigation, VISION_POSITION_DELTA as body odometry) and PX4 reads no "
        "VISION_POSITION_DELTA: choose one (for ArduPilot's deltas set link.odometry: false)");
  (void)parse_ekf_origin(c.link.ekf_origin);
}

std::optional<GeoPoint> parse_ekf_origin(const std::string& text) {
  if (text.find_first_not_of(" \t") == std::string::npos) return std::nullopt;
  const auto bad = [&](const std::string& why) {
    return ConfigError("config key 'link.ekf_origin': " + why + " (expected \"LATITUDE_DEG, LONGITUDE_DEG, ALTITUDE_M\", got '" +
                       text + "')");
  };
  std::vector<double> values;
  std::stringstream list(text);
  for (std::string item; std::getline(list, item, ',');) {
    const auto first = item.find_first_not_of(" \t"), last = item.find_last_not_of(" \t");
    if (first == std::string::npos) throw bad("an empty value");
    item = item.substr(first, last - first + 1);
    double v = 0;
    const char* end = item.data() + item.size();
    const auto [ptr, ec] = std::from_chars(item.data(), end, v);
    if (ec != std::errc() || ptr != end || !std::isfinite(v)) throw bad("'" + item + "' is not a number");
    values.push_back(v);
  }
  if (values.size() != 3) throw bad("3 values needed");
  if (std::abs(values[0]) > 90) throw bad("latitude outside [-90, 90] degrees");
  if (std::abs(values[1]) > 180) throw bad("longitude outside [-180, 180] degrees");
  if (values[2] < -1000 || values[2] > 10000) throw bad("altitude outside [-1000, 10000] m");
  return GeoPoint{values[0], values[1], values[2]};
}

std::vector<int> parse_cpu_list(const std::string& text) {
  std::vector<int> cpus;
  std::stringstream list(text);
  for (std::string item; std::getline(list, item, ',');) {
    int cpu = -1;
    const char* end = item.data() + item.size();
    auto [ptr, ec] = std::from_chars(item.data(), end, cpu);
    if (ec != std::errc() || ptr != end || cpu < 0 || cpu > 1023)
      throw ConfigError("config key 'runtime.cpu_affinity': expected CPU numbers like \"4,5,6,7\", got '" + text + "'");
    cpus.push_back(cpu);
  }
  return cpus;
}

}  // namespace rgbdo
