#include "rgbd_odometry/link/autopilot_watch.hpp"

namespace rgbdo {

const char* autopilot_name(std::uint8_t mav_autopilot) {
  switch (mav_autopilot) {
    case mavlink::kMavAutopilotPx4: return "PX4";
    case mavlink::kMavAutopilotArdupilotmega: return "ArduPilot";
    default: return "autopilot";
  }
}

bool AutopilotWatch::accept(const mavlink::ReceivedFrame& frame, std::int64_t now_ns) {
  if ((frame.sysid == own_system_ && frame.compid == own_component_) || (wanted_ != 0 && frame.sysid != wanted_)) {
    ++ignored_;
    return false;
  }
  const bool from_followed = known_ && frame.sysid == identity_.system_id;
  if (frame.msgid == mavlink::Heartbeat::kId) {
    const mavlink::Heartbeat hb = mavlink::unpack_heartbeat(frame.payload);
    const bool is_autopilot = hb.autopilot != mavlink::kMavAutopilotInvalid;
    const bool same = from_followed && frame.compid == identity_.component_id;
    // A new autopilot only when none is followed or the followed one has gone quiet.
    if (is_autopilot && (same || !up(now_ns))) {
      known_ = true;
      identity_ = {frame.sysid, frame.compid, hb.autopilot, hb.type};
      last_heartbeat_ns_ = now_ns;
      ++heartbeats_;
    }
  }
  if (known_ && frame.sysid == identity_.system_id && frame.compid == identity_.component_id) last_frame_ns_ = now_ns;
  if (!known_) return true;  // nobody followed yet: anyone may become the autopilot
  if (frame.sysid != identity_.system_id) {
    ++ignored_;
    return false;
  }
  return true;
}

AutopilotState AutopilotWatch::state(std::int64_t now_ns) const {
  AutopilotState s;
  s.known = known_;
  s.up = up(now_ns);
  s.identity = identity_;
  s.last_heartbeat_ns = last_heartbeat_ns_;
  s.last_frame_ns = last_frame_ns_;
  s.heartbeats = heartbeats_;
  s.ignored_frames = ignored_;
  return s;
}

}  // namespace rgbdo
