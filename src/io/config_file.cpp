#include "rgbd_odometry/io/config_file.hpp"

#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/core/persistence.hpp>

namespace rgbdo {
namespace {

// OpenCV's YAML reader keeps "value  # comment" whole for unquoted strings and booleans.
std::string without_comment(std::string text) {
  for (size_t i = 1; i < text.size(); ++i)
    if (text[i] == '#' && (text[i - 1] == ' ' || text[i - 1] == '\t')) {
      text.resize(i);
      break;
    }
  while (!text.empty() && (text.back() == ' ' || text.back() == '\t')) text.pop_back();
  return text;
}

ConfigValue value_of(const std::string& key, const cv::FileNode& node) {
  if (node.isString()) return without_comment(static_cast<std::string>(node));
  if (node.isInt() || node.isReal()) return static_cast<double>(node);
  throw ConfigError("config key '" + key + "': expected a number, a string or true/false");
}

void set_from_node(Config& c, const std::string& path, const std::string& key, const cv::FileNode& node) {
  if (!set_config_value(c, key, value_of(key, node)))
    throw ConfigError("config file '" + path + "': unknown key '" + key + "'");
}

// Intrinsics from an OpenCV calibration file (calibrateCamera's usual output keys).
void load_calibration_file(Config& c, const std::string& path) {
  cv::FileStorage fs;
  try {
    fs.open(path, cv::FileStorage::READ);
  } catch (const cv::Exception& e) {
    throw ConfigError("camera.calibration_file '" + path + "': cannot parse: " + e.what());
  }
  if (!fs.isOpened())
    throw ConfigError("camera.calibration_file '" + path + "': cannot open");
  cv::Mat K, dist;
  fs["camera_matrix"] >> K;
  fs["distortion_coefficients"] >> dist;
  if (K.rows != 3 || K.cols != 3)
    throw ConfigError("camera.calibration_file '" + path + "': 'camera_matrix' must be 3x3");
  K.convertTo(K, CV_64F);
  c.camera.fx = K.at<double>(0, 0);
  c.camera.fy = K.at<double>(1, 1);
  c.camera.cx = K.at<double>(0, 2);
  c.camera.cy = K.at<double>(1, 2);
  if (!dist.empty()) {
    if (dist.total() < 4 || dist.total() > 5)
      throw ConfigError("camera.calibration_file '" + path +
                        "': 'distortion_coefficients' must hold 4 or 5 values (k1 k2 p1 p2 [k3])");
    dist.convertTo(dist, CV_64F);
    c.camera.distortion = {0, 0, 0, 0, 0};
    for (size_t i = 0; i < dist.total(); ++i) c.camera.distortion[i] = dist.at<double>(static_cast<int>(i));
  }
  int w = 0, h = 0;
  fs["image_width"] >> w;
  fs["image_height"] >> h;
  if (w > 0) c.camera.width = w;
  if (h > 0) c.camera.height = h;
}

}  // namespace

Config load_config(const std::string& path) {
  if (!std::filesystem::exists(path))
    throw ConfigError("config file '" + path + "' does not exist");
  cv::FileStorage fs;
  try {
    fs.open(path, cv::FileStorage::READ | cv::FileStorage::FORMAT_YAML);
  } catch (const cv::Exception& e) {
    throw ConfigError("config file '" + path + "' is not valid YAML: " + e.what());
  }
  if (!fs.isOpened()) throw ConfigError("config file '" + path + "' cannot be opened as YAML");

  Config c;
  const cv::FileNode root = fs.root();
  if (!root.isMap()) throw ConfigError("config file '" + path + "' must hold a mapping of sections");

  // The calibration file goes first so that explicit keys in this file still win.
  const cv::FileNode calib = root["camera"]["calibration_file"];
  if (!calib.empty()) {
    std::filesystem::path calib_path = static_cast<std::string>(calib);
    if (calib_path.is_relative()) calib_path = std::filesystem::path(path).parent_path() / calib_path;
    load_calibration_file(c, calib_path.string());
  }

  for (const std::string& section : root.keys()) {
    const cv::FileNode node = root[section];
    if (!node.isMap()) {
      set_from_node(c, path, section, node);
      continue;
    }
    for (const std::string& name : node.keys()) {
      const std::string key = section + "." + name;
      if (key == "camera.calibration_file") continue;
      if (key == "camera.distortion") {
        if (node[name].size() != 5)
          throw ConfigError("config key 'camera.distortion': expected 5 values [k1, k2, p1, p2, k3]");
        static const char* const kDistortionKeys[5] = {"camera.k1", "camera.k2", "camera.p1",
                                                       "camera.p2", "camera.k3"};
        for (int i = 0; i < 5; ++i) set_from_node(c, path, kDistortionKeys[i], node[name][i]);
        continue;
      }
      set_from_node(c, path, key, node[name]);
    }
  }
  return c;
}

}  // namespace rgbdo
