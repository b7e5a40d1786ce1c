#pragma once
// One RGB-D frame as the pipeline consumes it, whatever the source: the input every source
// (io/ for recordings, sensor/ for OpenNI2 devices) fills.
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <string>

#include "rgbd_odometry/core/status.hpp"

namespace rgbdo {

// Capture times are on the source's timeline: a recording's own times, or a live sensor's
// clock mapped continuously onto the host's (sensor/device_clock.hpp), whose intervals are
// the device's. A live timeline can run ahead of the host clock by host_lead_ns (known once a
// frame arrives before its mapped capture time): the host's capture time is t - host_lead_ns.
struct RgbdFrame {
  std::int64_t t_colour_ns = 0;  // capture time of the colour image
  std::int64_t t_depth_ns = 0;   // capture time of the depth image registered to it
  std::int64_t host_lead_ns = 0;
  std::int64_t host_colour_ns() const { return t_colour_ns - host_lead_ns; }
  cv::Mat gray;                  // CV_8UC1, the colour image converted to intensity
  cv::Mat depth_m;               // CV_32FC1 metres on the colour pixel grid, 0 = no reading
  Status status = Status::Ok;    // BadFrame / NoDepth when the source could not deliver
  std::string problem;           // for a failed frame: what was wrong, naming the file
};

}  // namespace rgbdo
