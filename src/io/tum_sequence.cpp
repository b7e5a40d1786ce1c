#include "rgbd_odometry/io/tum_sequence.hpp"

#include "rgbd_odometry/core/cost_stage.hpp"
#include "rgbd_odometry/pipeline/frame_convert.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <cstdint>
#include <utility>
#include <optional>
#include <cstring>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include "rgbd_odometry/core/time_format.hpp"

namespace rgbdo {
namespace fs = std::filesystem;

std::optional<std::int64_t> parse_timestamp_ns(const std::string& text) {
  const auto dot = text.find('.');
  const std::string whole = text.substr(0, dot);
  std::string frac = dot == std::string::npos ? "" : text.substr(dot + 1);
  if (whole.empty() || whole.size() > 11 || frac.size() > 9) return std::nullopt;
  if (!std::all_of(whole.begin(), whole.end(), ::isdigit) || !std::all_of(frac.begin(), frac.end(), ::isdigit))
    return std::nullopt;
  frac.resize(9, '0');
  // Nanoseconds in 64 bits reach the year 2262: a larger second count is no timestamp (an
  // 11-digit one overflowed here, found by fuzz_tum_sequence).
  const long long seconds = std::stoll(whole);
  if (seconds > 9'000'000'000LL) return std::nullopt;
  return seconds * 1'000'000'000LL + std::stoll(frac);
}

namespace {


struct IndexEntry {
  std::int64_t t_ns;
  std::vector<std::string> fields;  // the columns after the timestamp
};

std::vector<IndexEntry> read_index(const fs::path& file, size_t fields_expected, bool required) {
  std::ifstream in(file);
  if (!in) {
    if (required) throw SourceError("cannot open '" + file.string() + "'");
    return {};
  }
  std::vector<IndexEntry> entries;
  std::string line;
  for (int line_no = 1; std::getline(in, line); ++line_no) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    std::string stamp;
    words >> stamp;
    if (stamp.empty()) continue;
    IndexEntry e{};
    const auto t = parse_timestamp_ns(stamp);
    if (!t)
      throw SourceError(file.string() + ":" + std::to_string(line_no) + ": bad timestamp '" + stamp + "'");
    e.t_ns = *t;
    for (std::string w; words >> w;) e.fields.push_back(w);
    if (e.fields.size() != fields_expected)
      throw SourceError(file.string() + ":" + std::to_string(line_no) + ": expected " +
                        std::to_string(fields_expected + 1) + " columns, found " +
                        std::to_string(e.fields.size() + 1));
    if (!entries.empty() && e.t_ns < entries.back().t_ns)
      throw SourceError(file.string() + ":" + std::to_string(line_no) + ": timestamps go backwards");
    entries.push_back(std::move(e));
  }
  if (required && entries.empty()) throw SourceError("'" + file.string() + "' lists no frames");
  return entries;
}

GroundTruth read_groundtruth(const fs::path& file) {
  std::vector<StampedPose> poses;
  for (const auto& e : read_index(file, 7, /*required=*/false)) {
    double v[7];
    for (int i = 0; i < 7; ++i) {
      try {
        v[i] = std::stod(e.fields[i]);
      } catch (const std::exception&) {
        throw SourceError(file.string() + ": bad number '" + e.fields[i] + "'");
      }
    }
    Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);
    if (std::abs(q.norm() - 1.0) > 1e-2) throw SourceError(file.string() + ": quaternion is not unit length");
    StampedPose p;
    p.t_ns = e.t_ns;
    p.pose.linear() = q.normalized().toRotationMatrix();
    p.pose.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
    poses.push_back(p);
  }
  return GroundTruth(std::move(poses));
}

}  // namespace

std::int64_t groundtruth_gap_ns(const std::vector<StampedPose>& poses) {
  if (poses.size() < 2) return 0;
  std::vector<std::int64_t> intervals;
  intervals.reserve(poses.size() - 1);
  for (size_t i = 1; i < poses.size(); ++i) intervals.push_back(poses[i].t_ns - poses[i - 1].t_ns);
  const auto mid = intervals.begin() + static_cast<std::ptrdiff_t>(intervals.size() / 2);
  std::nth_element(intervals.begin(), mid, intervals.end());
  // Stamps reach 9e18 ns (parse_timestamp_ns), so three intervals can pass 64 bits: such a
  // threshold is "no gap" (found by fuzz_tum_sequence in CI).
  constexpr std::int64_t kMax = std::numeric_limits<std::int64_t>::max();
  return *mid > kMax / 3 ? kMax : 3 * *mid;
}

std::optional<Eigen::Isometry3d> GroundTruth::at(std::int64_t t_ns) const {
  if (poses_.empty() || t_ns < poses_.front().t_ns || t_ns > poses_.back().t_ns) return std::nullopt;
  auto hi = std::lower_bound(poses_.begin(), poses_.end(), t_ns,
                             [](const StampedPose& p, std::int64_t t) { return p.t_ns < t; });
  if (hi->t_ns == t_ns) return hi->pose;
  auto lo = hi - 1;
  if (hi->t_ns - lo->t_ns > gap_ns_) return std::nullopt;
  const double a = static_cast<double>(t_ns - lo->t_ns) / static_cast<double>(hi->t_ns - lo->t_ns);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  const Eigen::Quaterniond q0(lo->pose.linear()), q1(hi->pose.linear());
  T.linear() = q0.slerp(a, q1).toRotationMatrix();
  T.translation() = (1 - a) * lo->pose.translation() + a * hi->pose.translation();
  return T;
}

std::vector<TumImage> read_tum_images(const std::string& directory, const std::string& index_name) {
  const fs::path dir(directory);
  std::vector<TumImage> images;
  for (const auto& e : read_index(dir / index_name, 1, true)) images.push_back({e.t_ns, (dir / e.fields[0]).string()});
  return images;
}

TumSequence open_tum_sequence(const std::string& directory, std::int64_t max_offset_ns) {
  const fs::path dir(directory);
  if (!fs::is_directory(dir)) throw SourceError("TUM sequence directory '" + directory + "' does not exist");
  const auto colour = read_index(dir / "rgb.txt", 1, true);
  const auto depth = read_index(dir / "depth.txt", 1, true);

  TumSequence seq;
  seq.directory = directory;
  seq.groundtruth = read_groundtruth(dir / "groundtruth.txt");
  for (const auto& c : colour) {
    TumFrameRef ref;
    ref.t_colour_ns = c.t_ns;
    ref.colour_path = (dir / c.fields[0]).string();
    // Nearest depth timestamp; the index is sorted, so look either side of lower_bound.
    auto it = std::lower_bound(depth.begin(), depth.end(), c.t_ns,
                               [](const IndexEntry& e, std::int64_t t) { return e.t_ns < t; });
    const IndexEntry* best = nullptr;
    if (it != depth.end()) best = &*it;
    if (it != depth.begin() && (!best || c.t_ns - (it - 1)->t_ns < best->t_ns - c.t_ns)) best = &*(it - 1);
    if (best && std::llabs(best->t_ns - c.t_ns) <= max_offset_ns) {
      ref.t_depth_ns = best->t_ns;
      ref.depth_path = (dir / best->fields[0]).string();
    }
    seq.frames.push_back(std::move(ref));
  }
  return seq;
}

std::optional<std::pair<std::uint32_t, std::uint32_t>> png_declared_size(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char h[24] = {};
  if (!in.read(reinterpret_cast<char*>(h), sizeof h)) return std::nullopt;
  static const unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (std::memcmp(h, kSignature, 8) != 0 || std::memcmp(h + 12, "IHDR", 4) != 0) return std::nullopt;
  const auto be32 = [&](int at) {
    return (std::uint32_t{h[at]} << 24) | (std::uint32_t{h[at + 1]} << 16) | (std::uint32_t{h[at + 2]} << 8) | h[at + 3];
  };
  return std::pair{be32(16), be32(20)};
}

RgbdFrame load_tum_frame(const TumFrameRef& ref, double depth_units_per_m, int expected_width,
                         int expected_height) {
  const CostStagesEnd stages_end;
  mark_cost_stage(CostStage::Decode);
  RgbdFrame f;
  f.t_colour_ns = ref.t_colour_ns;
  f.t_depth_ns = ref.t_depth_ns.value_or(ref.t_colour_ns);
  const auto fail = [&](Status s, std::string why) {
    f.status = s;
    f.problem = std::move(why);
    f.gray.release();
    f.depth_m.release();
    return f;
  };
  // Decoded in colour and converted as frames from a live RGB sensor are (libpng's own grey
  // conversion differs in many pixels): replay and live agree.
  const auto declared_size_problem = [&](const std::string& path, const char* what) -> std::string {
    const auto size = png_declared_size(path);
    if (!size || (size->first == static_cast<std::uint32_t>(expected_width) && size->second == static_cast<std::uint32_t>(expected_height)))
      return {};
    return std::string(what) + " image '" + path + "' is " + std::to_string(size->first) + "x" + std::to_string(size->second) +
           " (its PNG header; not decoded), the camera is " + std::to_string(expected_width) + "x" + std::to_string(expected_height);
  };
  if (std::string why = declared_size_problem(ref.colour_path, "colour"); !why.empty()) return fail(Status::BadFrame, why);
  cv::Mat colour;
  try {
    const cv::Mat bgr = cv::imread(ref.colour_path, cv::IMREAD_COLOR);
    if (!bgr.empty()) {
      mark_cost_stage(CostStage::Convert);
      colour_to_gray(bgr, false, colour);
      mark_cost_stage(CostStage::Decode);
    }
  } catch (const cv::Exception& e) {
    return fail(Status::BadFrame, "cannot decode colour image '" + ref.colour_path + "': " + e.what());
  }
  if (colour.empty()) return fail(Status::BadFrame, "cannot read colour image '" + ref.colour_path + "'");
  if (colour.cols != expected_width || colour.rows != expected_height)
    return fail(Status::BadFrame, "colour image '" + ref.colour_path + "' is " + std::to_string(colour.cols) +
                                      "x" + std::to_string(colour.rows) + ", the camera is " +
                                      std::to_string(expected_width) + "x" + std::to_string(expected_height));
  f.gray = colour;
  if (!ref.t_depth_ns) return fail(Status::NoDepth, "no depth image within 20 ms of colour frame " + format_seconds(ref.t_colour_ns));

  if (std::string why = declared_size_problem(ref.depth_path, "depth"); !why.empty()) return fail(Status::BadFrame, why);
  cv::Mat raw;
  try {
    raw = cv::imread(ref.depth_path, cv::IMREAD_ANYDEPTH);
  } catch (const cv::Exception& e) {
    return fail(Status::BadFrame, "cannot decode depth image '" + ref.depth_path + "': " + e.what());
  }
  if (raw.empty()) return fail(Status::BadFrame, "cannot read depth image '" + ref.depth_path + "'");
  if (raw.type() != CV_16UC1)
    return fail(Status::BadFrame, "depth image '" + ref.depth_path + "' is not 16-bit single-channel");
  if (raw.size() != colour.size())
    return fail(Status::BadFrame, "depth image '" + ref.depth_path + "' does not match the colour image size");
  mark_cost_stage(CostStage::Convert);
  depth_to_metres(raw, 1.0 / depth_units_per_m, f.depth_m);
  return f;
}

}  // namespace rgbdo
