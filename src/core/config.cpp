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
  std::variant<int*, double*, bool*, std::string*, std::uint64_t*> target;
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  // Where zero is singular (a variance, a weight), min itself is refused: (min, max].
  bool above_min = false;
};

std::vector<Param> param_table(Config& c) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  return {
      {"camera.width", &c.camera.width, 16, 8192},
      {"camera.height", &c.camera.height, 16, 8192},
      {"camera.fx", &c.camera.fx, 1, 1e5},
      {"camera.fy", &c.camera.fy, 1, 1e5},
      {"camera.cx", &c.camera.cx, 0, 8192},
      {"camera.cy", &c.camera.cy, 0, 8192},
      {"camera.k1", &c.camera.distortion[0], -100, 100},
      {"camera.k2", &c.camera.distortion[1], -100, 100},
      {"camera.p1", &c.camera.distortion[2], -1, 1},
      {"camera.p2", &c.camera.distortion[3], -1, 1},
      {"camera.k3", &c.camera.distortion[4], -100, 100},
      {"depth.units_per_m", &c.depth.units_per_m, 1e-3, 1e6},
      {"depth.min_m", &c.depth.min_m, 0.0, 100},
      {"depth.max_m", &c.depth.max_m, 0.01, 100},
      {"depth.edge_max_relative_step", &c.depth.edge_max_relative_step, 0.0, inf},
      {"depth.compensate_timing", &c.depth.compensate_timing},
      {"features.detector", &c.features.detector},
      {"features.descriptor", &c.features.descriptor},
      {"features.max_features", &c.features.max_features, 10, 100000},
      {"features.border_px", &c.features.border_px, 0, 1000},
      {"features.orb_levels", &c.features.orb_levels, 1, 16},
      {"features.orb_scale_factor", &c.features.orb_scale_factor, 1.01, 2.0},
      {"features.fast_threshold", &c.features.fast_threshold, 1, 255},
      {"matching.ratio", &c.matching.ratio, 1e-6, 1.0},
      {"matching.window_px", &c.matching.window_px, 0, 1e5},
      {"ransac.inlier_threshold_m", &c.ransac.inlier_threshold_m, 1e-5, 10},
      {"ransac.max_iterations", &c.ransac.max_iterations, 1, 1000000},
      {"ransac.refine_threshold", &c.ransac.refine_threshold},
      {"ransac.min_inliers", &c.ransac.min_inliers, 3, 1000000},
      {"ransac.adaptive_stop", &c.ransac.adaptive_stop},
      {"covariance.perturbations", &c.covariance.perturbations, 8, 100000},
      {"covariance.model", &c.covariance.model},
      {"covariance.depth_noise_coeff", &c.covariance.depth_noise_coeff, 1e-9, 1.0},
      {"covariance.depth_lateral_sigma_px", &c.covariance.depth_lateral_sigma_px, 0.0, 100},
      {"covariance.timing_sigma_s", &c.covariance.timing_sigma_s, -1, 1},
      {"covariance.resample_cell_px", &c.covariance.resample_cell_px, 0, 1e5},
      {"covariance.colour_latency_sigma_s", &c.covariance.colour_latency_sigma_s, 0, 1},
      {"covariance.depth_latency_sigma_s", &c.covariance.depth_latency_sigma_s, 0, 1},
      {"covariance.integration_window_s", &c.covariance.integration_window_s, 0, 3600},
      {"covariance.pixel_sigma_px", &c.covariance.pixel_sigma_px, 0.0, 100, true},  // 0: singular fit weights
      {"covariance.residual_variance_factor", &c.covariance.residual_variance_factor},
      {"covariance.scale", &c.covariance.scale, 1e-6, 1e6},
      {"sensor.fps", &c.sensor.fps, 1, 120},
      {"sensor.registration", &c.sensor.registration},
      {"sensor.frame_timeout_ms", &c.sensor.frame_timeout_ms, 100, 600000},
      {"sensor.pairing_wait_ms", &c.sensor.pairing_wait_ms, 0, 10000},
      {"sensor.reconnect_timeout_s", &c.sensor.reconnect_timeout_s, -1, 1e9},
      {"sensor.reconnect_interval_ms", &c.sensor.reconnect_interval_ms, 10, 600000},
      {"sensor.record_oni", &c.sensor.record_oni},
      {"runtime.processing_threads", &c.runtime.processing_threads, 1, 2},
      {"runtime.extraction_threads", &c.runtime.extraction_threads, 1, 8},
      {"log.max_total_mb", &c.log.max_total_mb, 0.01, 1e7},
      {"runtime.cpu_affinity", &c.runtime.cpu_affinity},
      {"body.camera_roll_deg", &c.body.camera_roll_deg, -180, 180},
      {"body.camera_pitch_deg", &c.body.camera_pitch_deg, -90, 90},
      {"body.camera_yaw_deg", &c.body.camera_yaw_deg, -180, 180},
      {"body.camera_x_m", &c.body.camera_x_m, -10, 10},
      {"body.camera_y_m", &c.body.camera_y_m, -10, 10},
      {"body.camera_z_m", &c.body.camera_z_m, -10, 10},
      {"link.uri", &c.link.uri},
      {"link.system_id", &c.link.system_id, 1, 255},
      {"link.odometry", &c.link.odometry},
      {"link.vision_position_delta", &c.link.vision_position_delta},
      {"link.quality_sigma_fail_m", &c.link.quality_sigma_fail_m, 1e-4, 10},
      {"link.velocity_error_min_mps", &c.link.velocity_error_min_mps, 0.0, 100, true},  // 0: an exact velocity to the EKF
      {"link.velocity_error_max_mps", &c.link.velocity_error_max_mps, 0.0, 100},
      {"link.autopilot_system_id", &c.link.autopilot_system_id, 0, 255},
      {"link.autopilot_timeout_s", &c.link.autopilot_timeout_s, 0.2, 60},
      {"link.timesync_rate_hz", &c.link.timesync_rate_hz, 0.0, 20},
      {"link.timesync_max_rtt_ms", &c.link.timesync_max_rtt_ms, 0.1, 10000},
      {"link.ekf_origin", &c.link.ekf_origin},
      {"link.delta_min_interval_ms", &c.link.delta_min_interval_ms, 0.0, 1000},
      {"seed", &c.seed, 0, 1.8e19},
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
  if (c.ransac.min_inliers < 3)
    throw ConfigError("config key 'ransac.min_inliers': a rigid motion needs at least 3");
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
