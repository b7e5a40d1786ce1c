#pragma once
// The frame feed a --source text names: tum:DIR (io/tum_feed.hpp), openni://[DEVICE-URI] or
// oni:FILE.oni (sensor/openni_feed.hpp, with the re-open policy of
// sensor/reconnecting_feed.hpp).
#include <memory>
#include <stdexcept>
#include <string>

#include "rgbd_odometry/pipeline/pipeline_config.hpp"
#include "rgbd_odometry/sensor/sensor_config.hpp"
#include "rgbd_odometry/io/frame_feed.hpp"
#include "rgbd_odometry/io/tum_feed.hpp"
#include "rgbd_odometry/sensor/openni_feed.hpp"
#include "rgbd_odometry/sensor/reconnecting_feed.hpp"

namespace rgbdo {

// A --source text that names no source this program reads (a usage error, not a failure to open).
class SourceSpecError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// The feed a source text names:
//   tum:DIR                   a TUM RGB-D sequence directory (recorded: nothing skipped)
//   openni://[DEVICE-URI]     a live OpenNI2 device, the first one found when empty
//   oni:FILE.oni              an OpenNI2 recording played through OpenNI2's file driver
// Throws SourceSpecError for any other text, SourceError when the source cannot be opened.
std::unique_ptr<FrameFeed> open_frame_feed(const std::string& source, const PipelineConfig& config,
                                           const SensorConfig& sensor, int max_frames);

}  // namespace rgbdo
