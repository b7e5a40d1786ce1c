#pragma once
// Which autopilot is on the other end of the link, and whether it is still there, from the
// frames the receiver checked (mavlink_parser.hpp).
//
// The autopilot is the sender of a HEARTBEAT whose autopilot field is not
// MAV_AUTOPILOT_INVALID (a ground station or another companion sends that): its system id,
// component id and autopilot type (PX4 12, ArduPilot 3). With a configured system id only that
// system is followed; with 0 the first one heard is, and another may take over only after it
// went silent. It is up while frames keep coming from it (any checked frame proves it alive,
// not only the 1 Hz heartbeat, so a lost heartbeat is not a lost autopilot) and down once
// none came for `timeout_ns`.
//
// Frames of other systems are ignored (counted), and so are our own (a router or a broadcast
// network may echo them back). Not thread-safe: the owner guards it.
#include <cstdint>

#include "rgbd_odometry/link/mavlink_parser.hpp"

namespace rgbdo {

struct AutopilotIdentity {
  std::uint8_t system_id = 0, component_id = 0;
  std::uint8_t autopilot = 0;  // MAV_AUTOPILOT
  std::uint8_t type = 0;       // MAV_TYPE
  bool operator==(const AutopilotIdentity&) const = default;
};

struct AutopilotState {
  bool known = false;  // a heartbeat was heard (identity valid)
  bool up = false;     // known, and a frame came from it within the timeout
  AutopilotIdentity identity;
  std::int64_t last_heartbeat_ns = 0, last_frame_ns = 0;  // our clock; 0: never
  std::uint64_t heartbeats = 0;
  std::uint64_t ignored_frames = 0;  // other systems, or our own echoes
};

// "PX4", "ArduPilot", or "autopilot type N".
const char* autopilot_name(std::uint8_t mav_autopilot);

class AutopilotWatch {
 public:
  // wanted_system_id 0: follow the first autopilot heard.
  AutopilotWatch(std::uint8_t wanted_system_id, std::uint8_t own_system_id, std::uint8_t own_component_id,
                 std::int64_t timeout_ns)
      : wanted_(wanted_system_id), own_system_(own_system_id), own_component_(own_component_id),
        timeout_ns_(timeout_ns) {}

  // A checked frame arrived at now_ns. True when the program should act on it (it comes from
  // the followed system, or from one that may become it); false when it is to be ignored.
  bool accept(const mavlink::ReceivedFrame& frame, std::int64_t now_ns);
  AutopilotState state(std::int64_t now_ns) const;

 private:
  bool up(std::int64_t now_ns) const { return known_ && now_ns - last_frame_ns_ <= timeout_ns_; }

  std::uint8_t wanted_, own_system_, own_component_;
  std::int64_t timeout_ns_;
  bool known_ = false;
  AutopilotIdentity identity_;
  std::int64_t last_heartbeat_ns_ = 0, last_frame_ns_ = 0;
  std::uint64_t heartbeats_ = 0, ignored_ = 0;
};

}  // namespace rgbdo
