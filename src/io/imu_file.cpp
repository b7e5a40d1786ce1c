#include "rgbd_odometry/io/imu_file.hpp"

#include <charconv>
#include <cmath>
#include <optional>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "rgbd_odometry/io/tum_sequence.hpp"

namespace rgbdo {
namespace {

// A number as written (no locale); nullopt when the word is not one, entirely.
std::optional<double> number(const std::string& word) {
  double v = 0;
  const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), v);
  if (ec != std::errc() || end != word.data() + word.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

}  // namespace

ImuFile::ImuFile(const std::string& path) : path_(path) {
  std::ifstream in(path);
  if (!in) throw SourceError("cannot open the gyro file '" + path + "'");
  std::string line;
  for (int line_no = 1; std::getline(in, line); ++line_no) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    std::string word;
    if (!(words >> word)) continue;  // blank
    const auto where = [&] { return path + ":" + std::to_string(line_no) + ": "; };
    // The stamp exactly, as the frames' are read (integer nanoseconds); a negative one too.
    const bool negative = word[0] == '-';
    const auto t = parse_timestamp_ns(negative ? word.substr(1) : word);
    if (!t) throw SourceError(where() + "bad timestamp '" + word + "'");
    GyroSample s{negative ? -*t : *t, {}};
    for (int axis = 0; axis < 3; ++axis) {
      if (!(words >> word)) throw SourceError(where() + "expected 'timestamp wx wy wz', found fewer columns");
      const auto v = number(word);
      if (!v) throw SourceError(where() + "bad angular rate '" + word + "'");
      s.rate(axis) = *v;
    }
    if (!samples_.empty() && s.t_ns <= samples_.back().t_ns)
      throw SourceError(where() + "timestamp not after the line before");
    samples_.push_back(s);
  }
  if (samples_.empty()) throw SourceError("the gyro file '" + path + "' holds no samples");
}

std::size_t ImuFile::take(std::int64_t until_ns, std::span<GyroSample> out) {
  std::size_t n = 0;
  while (n < out.size() && next_ < samples_.size() && samples_[next_].t_ns <= until_ns) out[n++] = samples_[next_++];
  return n;
}

std::string ImuFile::description() const {
  const double span_s = static_cast<double>(samples_.back().t_ns - samples_.front().t_ns) * 1e-9;
  char text[64];
  std::snprintf(text, sizeof text, " (%zu samples, %.1f Hz)", samples_.size(),
                span_s > 0 ? static_cast<double>(samples_.size() - 1) / span_s : 0.0);
  return "'" + path_ + "'" + text;
}

}  // namespace rgbdo
