#pragma once
// The configuration as a file: YAML in OpenCV FileStorage syntax (deploy/config/*.yaml).
#include <string>

#include "rgbd_odometry/app/config.hpp"

namespace rgbdo {

// Reads a YAML file. Keys absent from the file keep their defaults; an unknown key is an
// error (a typo must not silently fly with a default). `camera.calibration_file` may name an
// OpenCV calibration file whose `camera_matrix` and `distortion_coefficients` provide the
// intrinsics. Throws ConfigError naming the file or key.
Config load_config(const std::string& path);

// The whole configuration as a commented file load_config() reads back to the same values
// (rgbd-odometry --print-config): every key, its unit, range and one line of help.
std::string config_yaml(const Config& config);

// The configuration reference, deploy/config/README.md (rgbd-odometry --print-config-reference):
// every key with its default, unit, range and help, as a Markdown table. A test keeps the
// file equal to it.
std::string config_reference_markdown();

}  // namespace rgbdo
