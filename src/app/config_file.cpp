#include "rgbd_odometry/app/config_file.hpp"

#include <cstdio>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>
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

// An OpenCV matrix node of at most max_elements values (empty when absent). Its declared size
// is checked before OpenCV allocates it: a file declaring 10^9 rows must not take the memory
// (found by fuzz_config_file).
cv::Mat small_matrix(const cv::FileNode& node, const std::string& path, const char* name, int max_elements) {
  if (node.empty()) return {};
  const auto refuse = [&](const std::string& why) {
    return ConfigError("camera.calibration_file '" + path + "': '" + name + "' " + why);
  };
  if (!node.isMap()) throw refuse("is not an OpenCV matrix (rows, cols, dt, data)");
  const cv::FileNode rows_node = node["rows"], cols_node = node["cols"];
  if (!rows_node.isInt() || !cols_node.isInt()) throw refuse("has no whole-number rows and cols");
  const int rows = static_cast<int>(rows_node), cols = static_cast<int>(cols_node);
  if (rows <= 0 || cols <= 0 || static_cast<long long>(rows) * cols > max_elements)
    throw refuse("declares " + std::to_string(rows) + " x " + std::to_string(cols) + " values (at most " +
                 std::to_string(max_elements) + ")");
  cv::Mat m;
  node >> m;
  return m;
}

// What this program's configuration and calibration files look like, checked before OpenCV's
// YAML reader sees either: that reader hangs for ever on some malformed files (a line of dashes
// after an indented first entry, or in place of the document marker, or text after the marker
// on its line: found by fuzz_config_file, the last in a calibration file), so what it cannot be
// given is refused here. One document ("---" once, before the first entry; '%' directives
// only before it), entries starting at the beginning of a line, text without NUL bytes, at
// most 1 MB. `what` names the file in the error: "config file" or "camera.calibration_file".
void check_layout(const std::string& what, const std::string& path) {
  constexpr std::uintmax_t kMaxBytes = 1 << 20;
  std::error_code ec;
  const std::uintmax_t bytes = std::filesystem::file_size(path, ec);
  if (ec) throw ConfigError(what + " '" + path + "' cannot be read: " + ec.message());
  if (bytes > kMaxBytes) throw ConfigError(what + " '" + path + "' is larger than 1 MB: not a configuration");
  std::ifstream in(path, std::ios::binary);
  std::string line;
  int number = 0;
  bool marker = false, entry = false;
  const auto refuse = [&](const std::string& why) {
    return ConfigError(what + " '" + path + "' line " + std::to_string(number) + ": " + why);
  };
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find('\0') != std::string::npos) throw refuse("a NUL byte: not a text file");
    if (line.rfind("---", 0) == 0 || line.rfind("...", 0) == 0) {
      if (line != "---" || marker || entry) throw refuse("'" + line.substr(0, 8) + "': one YAML document, '---' once before the entries");
      marker = true;
      continue;
    }
    const auto first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    // A directive ('%YAML:1.0' and the like) heads the document; it is not its first entry,
    // which must still start at the line's beginning ('%' then an indented entry hung the reader).
    if (line[0] == '%') {
      if (marker || entry) throw refuse("a '%' directive inside the document; directives go before '---'");
      continue;
    }
    if (!entry && first != 0) throw refuse("the first entry is indented; sections start at the line's beginning");
    entry = true;
  }
}

// Intrinsics from an OpenCV calibration file (calibrateCamera's usual output keys).
void load_calibration_file(Config& c, const std::string& path) {
  check_layout("camera.calibration_file", path);
  cv::FileStorage fs;
  try {
    fs.open(path, cv::FileStorage::READ);
  } catch (const cv::Exception& e) {
    throw ConfigError("camera.calibration_file '" + path + "': cannot parse: " + e.what());
  }
  if (!fs.isOpened())
    throw ConfigError("camera.calibration_file '" + path + "': cannot open");
  const cv::Mat K = small_matrix(fs["camera_matrix"], path, "camera_matrix", 9);
  cv::Mat dist = small_matrix(fs["distortion_coefficients"], path, "distortion_coefficients", 5);
  if (K.rows != 3 || K.cols != 3)
    throw ConfigError("camera.calibration_file '" + path + "': 'camera_matrix' must be 3x3");
  cv::Mat K64;
  K.convertTo(K64, CV_64F);
  c.camera.fx = K64.at<double>(0, 0);
  c.camera.fy = K64.at<double>(1, 1);
  c.camera.cx = K64.at<double>(0, 2);
  c.camera.cy = K64.at<double>(1, 2);
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

Config parse_config_file(const std::string& path) {
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
  const cv::FileNode camera = root["camera"];
  const cv::FileNode calib = camera.isMap() ? camera["calibration_file"] : cv::FileNode();
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
      if (key == "link.ekf_origin" && node[name].isSeq()) {
        // [lat, lon, alt] -> the key's text form, every digit kept (1e-7 deg is ~1 cm).
        std::string text;
        for (const auto& value : node[name]) {
          if (!value.isReal() && !value.isInt())
            throw ConfigError("config key 'link.ekf_origin' in '" + path + "': expected numbers [lat, lon, alt]");
          char number[32];
          std::snprintf(number, sizeof number, "%.12g", static_cast<double>(value));
          text += (text.empty() ? "" : ", ") + std::string(number);
        }
        set_config_value(c, key, ConfigValue{text});
        continue;
      }
      set_from_node(c, path, key, node[name]);
    }
  }
  return c;
}

}  // namespace

Config load_config(const std::string& path) {
  if (!std::filesystem::exists(path))
    throw ConfigError("config file '" + path + "' does not exist");
  // OpenCV's reader asserts on shapes it does not expect and lets standard exceptions out of
  // its parser (both found by fuzz_config_file): what they say is still about this file.
  check_layout("config file", path);
  try {
    return parse_config_file(path);
  } catch (const ConfigError&) {
    throw;
  } catch (const cv::Exception& e) {
    throw ConfigError("config file '" + path + "' cannot be read: " + e.err);
  } catch (const std::exception& e) {
    throw ConfigError("config file '" + path + "' cannot be read: " + e.what());
  }
}

namespace {

// "camera.width" -> ("camera", "width"); "seed" -> ("", "seed").
std::pair<std::string, std::string> split_key(const std::string& key) {
  const auto dot = key.find('.');
  if (dot == std::string::npos) return {"", key};
  return {key.substr(0, dot), key.substr(dot + 1)};
}

std::string unit_and_range(const ConfigKeyInfo& k) {
  std::string text = k.unit;
  if (!k.range.empty()) text += (text.empty() ? "" : ", ") + k.range;
  return text;
}

}  // namespace

std::string config_yaml(const Config& config) {
  std::ostringstream out;
  out << "%YAML:1.0\n---\n"
         "# rgbd-odometry's whole configuration (rgbd-odometry --print-config): every key with its\n"
         "# value, unit and range; deploy/config/README.md explains each. --config reads it back.\n";
  std::string section;
  for (const ConfigKeyInfo& k : describe_config(config)) {
    const auto [key_section, name] = split_key(k.key);
    if (key_section != section) {
      section = key_section;
      if (!section.empty()) out << section << ":\n";
    }
    const std::string indent = section.empty() ? "" : "  ";
    const std::string bracket = unit_and_range(k);
    out << indent << "# " << k.help << (bracket.empty() ? "" : " (" + bracket + ")") << "\n";
    out << indent << name << ": " << (k.kind == ConfigKeyInfo::Kind::Text ? "\"" + k.value + "\"" : k.value) << "\n";
  }
  return out.str();
}

std::string config_reference_markdown() {
  std::ostringstream out;
  out << "# Configuration reference\n\n"
         "Generated from the keys each layer registers (put together in `src/app/config.cpp`) by\n"
         "`rgbd-odometry --print-config-reference`;\n"
         "`test_config` keeps this file equal to it. A configuration file is YAML in OpenCV's FileStorage\n"
         "syntax (`%YAML:1.0`, then `---`), grouped by section; every key is optional, and an unknown key,\n"
         "a wrong type or a value out of range is refused at start-up with a message naming it. On the\n"
         "command line `--set section.key=value` overrides the file. `rgbd-odometry --print-config\n"
         "[--config FILE] [--set ...]` prints the whole effective configuration in this form, and\n"
         "`--config` reads that output back. Two more spellings in a file: `camera.distortion: [k1, k2,\n"
         "p1, p2, k3]` and `link.ekf_origin: [lat, lon, alt]`; and `camera.calibration_file` names an\n"
         "OpenCV calibration file (`camera_matrix`, `distortion_coefficients`) for the intrinsics.\n\n"
         "Shipped: [`tum-fr1.yaml`](tum-fr1.yaml) and [`tum-fr3.yaml`](tum-fr3.yaml) (TUM RGB-D freiburg1\n"
         "and freiburg3 recordings), [`icl-nuim.yaml`](icl-nuim.yaml) (ICL-NUIM's rendered frames) and\n"
         "[`xtion.yaml`](xtion.yaml) (an Asus Xtion on the Odroid-XU3, installed by the package).\n\n"
         "| key | default | unit, range | what it does |\n| --- | --- | --- | --- |\n";
  for (const ConfigKeyInfo& k : describe_config(Config{})) {
    std::string help = k.help;
    for (std::size_t at = help.find('|'); at != std::string::npos; at = help.find('|', at + 2)) help.replace(at, 1, "\\|");
    out << "| `" << k.key << "` | " << (k.value.empty() ? "(empty)" : "`" + k.value + "`") << " | " << unit_and_range(k)
        << " | " << help << " |\n";
  }
  return out.str();
}

}  // namespace rgbdo
