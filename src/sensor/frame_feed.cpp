#include "rgbd_odometry/sensor/frame_feed.hpp"

namespace rgbdo {

std::unique_ptr<FrameFeed> open_frame_feed(const std::string& source, const PipelineConfig& config,
                                           const SensorConfig& sensor, int max_frames) {
  const std::string tum_scheme = "tum:", openni_scheme = "openni://", oni_scheme = "oni:";
  if (source.rfind(tum_scheme, 0) == 0)
    return std::make_unique<TumFeed>(open_tum_sequence(source.substr(tum_scheme.size())), config, max_frames);
  const bool file = source.rfind(oni_scheme, 0) == 0;
  if (!file && source.rfind(openni_scheme, 0) != 0)
    throw SourceSpecError("unsupported source '" + source +
                          "': expected tum:DIR (a TUM RGB-D sequence directory), openni://[DEVICE-URI] or oni:FILE.oni");
  OpenNiOptions o;
  o.uri = source.substr(file ? oni_scheme.size() : openni_scheme.size());
  if (file && (o.uri.size() < 5 || o.uri.compare(o.uri.size() - 4, 4, ".oni") != 0))
    throw SourceSpecError("oni:FILE needs a file ending in .oni, got '" + o.uri + "'");
  o.width = config.camera.width;
  o.height = config.camera.height;
  o.fps = sensor.fps;
  o.registration = sensor.registration;
  o.frame_timeout_ms = sensor.frame_timeout_ms;
  o.pairing_wait_ms = sensor.pairing_wait_ms;
  o.record_path = sensor.record_oni;
  return std::make_unique<ReconnectingFeed>(std::make_unique<OpenNiFeed>(o, max_frames), sensor);
}

}  // namespace rgbdo
