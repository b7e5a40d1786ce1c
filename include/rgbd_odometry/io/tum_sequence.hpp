#pragma once
// Reader for TUM RGB-D benchmark directories: rgb.txt, depth.txt, optional groundtruth.txt.
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "rgbd_odometry/pipeline/frame.hpp"

namespace rgbdo {

struct TumFrameRef {
  std::int64_t t_colour_ns = 0;
  std::string colour_path;
  std::optional<std::int64_t> t_depth_ns;  // empty: no depth image within the association window
  std::string depth_path;
};

struct StampedPose {
  std::int64_t t_ns = 0;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // camera in the world frame
};

// Where motion capture lost the camera: samples further apart than three times the median
// interval (30 ms at TUM's 100 Hz). Interpolating across such a gap is not a measurement:
// fr1_xyz has one of 110 ms at 1305031108.84, during a turn, where the interpolated rotation
// is off by several mrad, far beyond the samples' own noise.
std::int64_t groundtruth_gap_ns(const std::vector<StampedPose>& poses);

// Motion-capture ground truth, interpolated (linear + slerp) at arbitrary times.
class GroundTruth {
 public:
  GroundTruth() = default;
  explicit GroundTruth(std::vector<StampedPose> poses)
      : poses_(std::move(poses)), gap_ns_(groundtruth_gap_ns(poses_)) {}
  bool empty() const { return poses_.empty(); }
  size_t size() const { return poses_.size(); }
  const std::vector<StampedPose>& poses() const { return poses_; }
  // Empty when t lies outside the recording or in a gap (groundtruth_gap_ns).
  std::optional<Eigen::Isometry3d> at(std::int64_t t_ns) const;

 private:
  std::vector<StampedPose> poses_;
  std::int64_t gap_ns_ = 0;
};

struct TumSequence {
  std::string directory;
  std::vector<TumFrameRef> frames;  // one per colour image, in time order
  GroundTruth groundtruth;
};

class SourceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One line of a TUM index file (rgb.txt, depth.txt): a capture time and its image.
struct TumImage {
  std::int64_t t_ns = 0;
  std::string path;  // joined to the sequence directory
};

// Reads DIRECTORY/index_name ("rgb.txt", "depth.txt"). Throws SourceError naming the file and
// line when it is missing, empty or malformed (bad timestamp, wrong column count, time going
// backwards).
std::vector<TumImage> read_tum_images(const std::string& directory, const std::string& index_name);

// Colour and depth are associated by nearest timestamp, at most max_offset_ns apart.
// Throws SourceError naming the file and line on missing or malformed index files.
TumSequence open_tum_sequence(const std::string& directory, std::int64_t max_offset_ns = 20'000'000);

// Decodes one frame. Never throws: an unreadable or wrongly sized image gives
// status BadFrame, a missing depth association NoDepth.
// The size (width, height) a PNG file declares in its IHDR chunk, read before any decoding:
// a recording's 20000 x 20000 frame is refused from its header, not after 2.4 GB of
// decoding. Empty for a file that is not a PNG (OpenCV's decoders judge those).
std::optional<std::pair<std::uint32_t, std::uint32_t>> png_declared_size(const std::string& path);

RgbdFrame load_tum_frame(const TumFrameRef& ref, double depth_units_per_m, int expected_width,
                         int expected_height);

// Parses "1305031102.175304" into nanoseconds without going through a double.
std::optional<std::int64_t> parse_timestamp_ns(const std::string& text);

}  // namespace rgbdo
