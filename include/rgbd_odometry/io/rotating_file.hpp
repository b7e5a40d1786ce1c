#pragma once
// A file a run writes beside the files of earlier runs (the odometry log, the trajectory), so
// that a restart after a failure never erases the log of the run that failed, and so that
// the logs cannot fill the disk:
//   - an existing FILE is kept as FILE.1 (FILE.1 as FILE.2, ...) before the run starts FILE;
//   - a run's file is split when it reaches a quarter of the bound (the next part in FILE,
//     the earlier parts kept as FILE.1, ...), each part opening with the header;
//   - FILE and its kept predecessors together stay within max_total_bytes after every line:
//     the oldest kept files are removed first;
//   - every line is flushed as written: a crash loses at most the line being written.
#include <cstdint>
#include <fstream>
#include <string>

namespace rgbdo {

class RotatingFile {
 public:
  // Throws std::runtime_error naming the file when it cannot be created or rotated.
  RotatingFile(std::string path, std::uint64_t max_total_bytes, std::string header);
  // Writes line + '\n'; throws std::runtime_error naming the file when it cannot.
  void write_line(const std::string& line);
  const std::string& path() const { return path_; }

 private:
  void start_part();  // keeps FILE as FILE.1 (shifting the others) and opens FILE afresh
  void prune();       // removes the oldest kept files while the total exceeds the bound

  std::string path_, header_;
  std::uint64_t max_total_bytes_, part_bytes_limit_;
  std::uint64_t part_bytes_ = 0;  // of FILE
  std::uint64_t kept_bytes_ = 0;  // of FILE.1, FILE.2, ...
  std::ofstream out_;
};

}  // namespace rgbdo
