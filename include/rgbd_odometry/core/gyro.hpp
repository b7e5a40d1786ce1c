#pragma once
// The autopilot's angular rate, as the odometry reads it: samples on our clock (the clock the
// frames' capture times are on), body FRD, rad/s. Live, the flight link maps the autopilot's
// ATTITUDE rates onto our clock through TIMESYNC; a replay reads them from an `imu.txt` file
// on the recording's clock (io/imu_file.hpp). The odometry uses them to learn when its frames
// were taken (pipeline/capture_latency.hpp), never to change a motion.
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace rgbdo {

struct GyroSample {
  std::int64_t t_ns = 0;                          // our clock
  Eigen::Vector3d rate = Eigen::Vector3d::Zero();  // body FRD, rad/s
};

// Where gyro samples come from. Called from one thread (the estimation thread).
class GyroFeed {
 public:
  virtual ~GyroFeed() = default;
  // Moves the samples stamped no later than until_ns into `out`, oldest first, at most
  // out.size() of them; returns how many. A live feed hands over what has arrived.
  virtual std::size_t take(std::int64_t until_ns, std::span<GyroSample> out) = 0;
  // "imu.txt (1486 samples, 50.0 Hz)", "the autopilot's ATTITUDE": for the summary.
  virtual std::string description() const = 0;
};

}  // namespace rgbdo
