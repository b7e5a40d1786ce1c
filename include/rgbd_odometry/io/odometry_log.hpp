#pragma once
// The project's outputs on disk: the odometry log (shared/docs/odometry-csv.md, one row per
// colour-frame pair, failed pairs included) and the integrated trajectory in TUM format.
#include <Eigen/Geometry>
#include <cstdint>
#include <fstream>
#include <string>

#include "rgbd_odometry/core/pair_result.hpp"

namespace rgbdo {

class OdometryCsvWriter {
 public:
  // Throws std::runtime_error naming the file when it cannot be created.
  explicit OdometryCsvWriter(const std::string& path);
  void write(const PairResult& r);  // flushed per row: a crash must not lose written pairs
  static std::string header();
  static std::string row(const PairResult& r);

 private:
  std::string path_;
  std::ofstream out_;
};

class TrajectoryWriter {
 public:
  explicit TrajectoryWriter(const std::string& path);
  void write(std::int64_t t_ns, const Eigen::Isometry3d& pose);

 private:
  std::string path_;
  std::ofstream out_;
};

}  // namespace rgbdo
