#pragma once
// One RGB-D frame as the pipeline consumes it, whatever the source: the input every source
// (io/ for recordings, sensor/ for OpenNI2 devices) fills.
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <string>

#include "rgbd_odometry/core/status.hpp"

namespace rgbdo {

struct RgbdFrame {
  std::int64_t t_colour_ns = 0;  // capture time of the colour image
  std::int64_t t_depth_ns = 0;   // capture time of the depth image registered to it
  cv::Mat gray;                  // CV_8UC1, the colour image converted to intensity
  cv::Mat depth_m;               // CV_32FC1 metres on the colour pixel grid, 0 = no reading
  Status status = Status::Ok;    // BadFrame / NoDepth when the source could not deliver
  std::string problem;           // for a failed frame: what was wrong, naming the file
};

}  // namespace rgbdo
