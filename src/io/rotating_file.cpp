#include "rgbd_odometry/io/rotating_file.hpp"

#include <algorithm>
#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace rgbdo {
namespace fs = std::filesystem;
namespace {

std::string kept_name(const std::string& path, int k) { return path + "." + std::to_string(k); }

// The number of kept files FILE.1 .. FILE.n (a gap ends the series).
int kept_count(const std::string& path) {
  int n = 0;
  std::error_code ec;
  while (fs::exists(kept_name(path, n + 1), ec)) ++n;
  return n;
}

}  // namespace

RotatingFile::RotatingFile(std::string path, std::uint64_t max_total_bytes, std::string header)
    : path_(std::move(path)),
      header_(std::move(header)),
      max_total_bytes_(max_total_bytes),
      part_bytes_limit_(std::max<std::uint64_t>(max_total_bytes / 4, 1)) {
  start_part();
}

void RotatingFile::start_part() {
  if (out_.is_open()) out_.close();
  std::error_code ec;
  // Only a regular file is kept: a device or a pipe (/dev/null, a FIFO to a logger) is
  // written as it is.
  if (fs::is_regular_file(path_, ec)) {
    for (int k = kept_count(path_); k >= 1; --k) {
      fs::rename(kept_name(path_, k), kept_name(path_, k + 1), ec);
      if (ec) throw std::runtime_error("cannot keep '" + kept_name(path_, k) + "' as '" + kept_name(path_, k + 1) + "': " + ec.message());
    }
    fs::rename(path_, kept_name(path_, 1), ec);
    if (ec) throw std::runtime_error("cannot keep the earlier '" + path_ + "' as '" + kept_name(path_, 1) + "': " + ec.message());
  }
  kept_bytes_ = 0;
  for (int k = kept_count(path_); k >= 1; --k)
    kept_bytes_ += static_cast<std::uint64_t>(fs::file_size(kept_name(path_, k), ec));
  out_.open(path_, std::ios::out | std::ios::trunc);
  if (!out_) throw std::runtime_error("cannot create output file '" + path_ + "'");
  part_bytes_ = 0;
  if (!header_.empty()) write_line(header_);
}

void RotatingFile::prune() {
  std::error_code ec;
  // Oldest (highest number) first.
  for (int k = kept_count(path_); k >= 1 && part_bytes_ + kept_bytes_ > max_total_bytes_; --k) {
    const auto size = static_cast<std::uint64_t>(fs::file_size(kept_name(path_, k), ec));
    if (!fs::remove(kept_name(path_, k), ec) || ec)
      throw std::runtime_error("cannot remove the old '" + kept_name(path_, k) + "' to bound the logs: " + ec.message());
    kept_bytes_ -= std::min(size, kept_bytes_);
  }
}

void RotatingFile::write_line(const std::string& line) {
  if (part_bytes_ > 0 && part_bytes_ + line.size() + 1 > part_bytes_limit_ && fs::is_regular_file(path_)) start_part();
  out_ << line << '\n' << std::flush;
  if (!out_) throw std::runtime_error("cannot write to '" + path_ + "' (disk full or file removed?)");
  part_bytes_ += line.size() + 1;
  if (part_bytes_ + kept_bytes_ > max_total_bytes_) prune();
}

}  // namespace rgbdo
