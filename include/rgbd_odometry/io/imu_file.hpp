#pragma once
// A recording's gyro for replays: `imu.txt` beside rgb.txt (or --imu FILE). Lines of
//     timestamp wx wy wz [more columns, ignored]
// seconds on the recording's clock (the frames' stamps' clock), body FRD angular rate in rad/s;
// lines starting with '#' and empty lines are skipped. What an autopilot's gyro measured while
// the recording was made; ../shared/tools/imu-from-groundtruth/make_imu.py writes one from a
// TUM ground truth. The odometry measures its frames' capture latency against it
// (pipeline/capture_latency.hpp).
#include <cstddef>
#include <string>
#include <vector>

#include "rgbd_odometry/core/gyro.hpp"

namespace rgbdo {

// Read whole at start-up; hands the samples out as the replay reaches them.
class ImuFile : public GyroFeed {
 public:
  // Throws SourceError (io/tum_sequence.hpp) naming the file and line: unreadable, a line with
  // fewer than four numbers, a timestamp not after the one before, no samples at all.
  explicit ImuFile(const std::string& path);

  std::size_t take(std::int64_t until_ns, std::span<GyroSample> out) override;
  std::string description() const override;
  const std::vector<GyroSample>& samples() const { return samples_; }

 private:
  std::string path_;
  std::vector<GyroSample> samples_;
  std::size_t next_ = 0;
};

}  // namespace rgbdo
