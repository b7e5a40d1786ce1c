#pragma once
// The project's outputs on disk: the odometry log (src/io/LOG_FORMAT.md, one row per
// colour-frame pair, failed pairs included) and the integrated trajectory in TUM format.
#include <Eigen/Geometry>
#include <cstdint>
#include <limits>
#include <string>

#include "rgbd_odometry/core/pair_result.hpp"
#include "rgbd_odometry/io/rotating_file.hpp"

namespace rgbdo {

// No bound on the kept logs (tests, one-off replays); the program passes log.max_total_mb.
inline constexpr std::uint64_t kUnboundedLogs = std::numeric_limits<std::uint64_t>::max();

// Both writers keep an earlier run's file as FILE.1 (and so on) and keep FILE with its
// predecessors within max_total_bytes (rotating_file.hpp).
class OdometryCsvWriter {
 public:
  // Throws std::runtime_error naming the file when it cannot be created.
  explicit OdometryCsvWriter(const std::string& path, std::uint64_t max_total_bytes = kUnboundedLogs);
  void write(const PairResult& r);  // flushed per row: a crash must not lose written pairs
  static std::string header();
  static std::string row(const PairResult& r);

 private:
  RotatingFile file_;
};

class TrajectoryWriter {
 public:
  explicit TrajectoryWriter(const std::string& path, std::uint64_t max_total_bytes = kUnboundedLogs);
  void write(std::int64_t t_ns, const Eigen::Isometry3d& pose);

 private:
  RotatingFile file_;
};

}  // namespace rgbdo
