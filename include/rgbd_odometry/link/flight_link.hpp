#pragma once
// The flight-computer feed: each pair result becomes MAVLink 2 ODOMETRY (and/or ArduPilot's
// VISION_POSITION_DELTA) on the configured link, with a HEARTBEAT every second. Runs on the
// pipeline's output thread; never blocks it (the link queues or drops, and says so).
#include <cstdint>
#include <memory>
#include <string>

#include "rgbd_odometry/core/config.hpp"
#include "rgbd_odometry/link/transport.hpp"
#include "rgbd_odometry/link/mavlink.hpp"
#include "rgbd_odometry/link/mavlink_odometry.hpp"

namespace rgbdo {

// The camera-to-body extrinsic of body.* (config.hpp).
CameraExtrinsic extrinsic_from(const BodyConfig& body);

class FlightLink {
 public:
  // Opens link.uri; throws LinkError naming the problem (a bad device path, say).
  explicit FlightLink(const Config& config);

  void send_pair(const PairResult& pair);  // status SensorLost marks a reset of the pose
  void tick(std::int64_t now_ns);          // the 1 Hz heartbeat; call often
  // What to tell the user at start: where it sends, and whether a serial line can carry it.
  std::string startup_report() const;
  // The link's newest problem, once each time a new one is reported; empty otherwise.
  std::string news();
  LinkStats stats() const { return link_->stats(); }

 private:
  void send(std::size_t bytes);

  LinkConfig config_;
  LinkOptions options_;  // parsed once: the link is opened from it
  std::unique_ptr<OutputLink> link_;
  OdometryMessageBuilder builder_;
  mavlink::Framer framer_;
  std::array<std::uint8_t, mavlink::kMaxFrameBytes> buffer_{};
  std::int64_t next_heartbeat_ns_ = 0;
  std::uint64_t problems_seen_ = 0;
};

}  // namespace rgbdo
