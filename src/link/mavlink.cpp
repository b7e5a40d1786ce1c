#include "rgbd_odometry/link/mavlink.hpp"

#include <bit>

namespace rgbdo::mavlink {
namespace {

// Bytes are built by shifting, never by copying a struct: the wire is little-endian whatever
// the host is, and MAVLink's field order is not C's layout.
void put_u8(std::span<std::uint8_t> out, std::size_t offset, std::uint8_t v) { out[offset] = v; }

void put_u16(std::span<std::uint8_t> out, std::size_t offset, std::uint16_t v) {
  out[offset] = static_cast<std::uint8_t>(v);
  out[offset + 1] = static_cast<std::uint8_t>(v >> 8);
}

void put_u32(std::span<std::uint8_t> out, std::size_t offset, std::uint32_t v) {
  for (std::size_t i = 0; i < 4; ++i) out[offset + i] = static_cast<std::uint8_t>(v >> (8 * i));
}

void put_u64(std::span<std::uint8_t> out, std::size_t offset, std::uint64_t v) {
  for (std::size_t i = 0; i < 8; ++i) out[offset + i] = static_cast<std::uint8_t>(v >> (8 * i));
}

void put_i64(std::span<std::uint8_t> out, std::size_t offset, std::int64_t v) {
  put_u64(out, offset, static_cast<std::uint64_t>(v));  // two's complement
}

std::uint64_t get_le(std::span<const std::uint8_t> in, std::size_t offset, std::size_t bytes) {
  std::uint64_t v = 0;
  for (std::size_t i = bytes; i-- > 0;) v = (v << 8) | in[offset + i];
  return v;
}

void put_f32(std::span<std::uint8_t> out, std::size_t offset, float v) {
  static_assert(std::numeric_limits<float>::is_iec559, "MAVLink floats are IEEE 754 binary32");
  put_u32(out, offset, std::bit_cast<std::uint32_t>(v));
}

template <std::size_t N>
void put_f32_array(std::span<std::uint8_t> out, std::size_t offset, const std::array<float, N>& v) {
  for (std::size_t i = 0; i < N; ++i) put_f32(out, offset + 4 * i, v[i]);
}

// The payload area of a frame buffer, sized for one message.
template <typename Message>
std::span<std::uint8_t, Message::kPayloadBytes> payload_area(FrameSpan frame) {
  return frame.subspan<kHeaderBytes, Message::kPayloadBytes>();
}

}  // namespace

void pack_payload(const Heartbeat& m, std::span<std::uint8_t, Heartbeat::kPayloadBytes> out) {
  put_u32(out, Heartbeat::kCustomModeOffset, m.custom_mode);
  put_u8(out, Heartbeat::kTypeOffset, m.type);
  put_u8(out, Heartbeat::kAutopilotOffset, m.autopilot);
  put_u8(out, Heartbeat::kBaseModeOffset, m.base_mode);
  put_u8(out, Heartbeat::kSystemStatusOffset, m.system_status);
  put_u8(out, Heartbeat::kMavlinkVersionOffset, m.mavlink_version);
}

void pack_payload(const Timesync& m, std::span<std::uint8_t, Timesync::kPayloadBytes> out) {
  put_i64(out, Timesync::kTc1Offset, m.tc1);
  put_i64(out, Timesync::kTs1Offset, m.ts1);
  put_u8(out, Timesync::kTargetSystemOffset, m.target_system);
  put_u8(out, Timesync::kTargetComponentOffset, m.target_component);
}

Heartbeat unpack_heartbeat(std::span<const std::uint8_t, kMaxPayloadBytes> payload) {
  Heartbeat m;
  m.custom_mode = static_cast<std::uint32_t>(get_le(payload, Heartbeat::kCustomModeOffset, 4));
  m.type = payload[Heartbeat::kTypeOffset];
  m.autopilot = payload[Heartbeat::kAutopilotOffset];
  m.base_mode = payload[Heartbeat::kBaseModeOffset];
  m.system_status = payload[Heartbeat::kSystemStatusOffset];
  m.mavlink_version = payload[Heartbeat::kMavlinkVersionOffset];
  return m;
}

Timesync unpack_timesync(std::span<const std::uint8_t, kMaxPayloadBytes> payload) {
  Timesync m;
  m.tc1 = static_cast<std::int64_t>(get_le(payload, Timesync::kTc1Offset, 8));
  m.ts1 = static_cast<std::int64_t>(get_le(payload, Timesync::kTs1Offset, 8));
  m.target_system = payload[Timesync::kTargetSystemOffset];
  m.target_component = payload[Timesync::kTargetComponentOffset];
  return m;
}

void pack_payload(const Odometry& m, std::span<std::uint8_t, Odometry::kPayloadBytes> out) {
  put_u64(out, Odometry::kTimeUsecOffset, m.time_usec);
  put_f32(out, Odometry::kXOffset, m.x);
  put_f32(out, Odometry::kYOffset, m.y);
  put_f32(out, Odometry::kZOffset, m.z);
  put_f32_array(out, Odometry::kQOffset, m.q);
  put_f32(out, Odometry::kVxOffset, m.vx);
  put_f32(out, Odometry::kVyOffset, m.vy);
  put_f32(out, Odometry::kVzOffset, m.vz);
  put_f32(out, Odometry::kRollspeedOffset, m.rollspeed);
  put_f32(out, Odometry::kPitchspeedOffset, m.pitchspeed);
  put_f32(out, Odometry::kYawspeedOffset, m.yawspeed);
  put_f32_array(out, Odometry::kPoseCovarianceOffset, m.pose_covariance);
  put_f32_array(out, Odometry::kVelocityCovarianceOffset, m.velocity_covariance);
  put_u8(out, Odometry::kFrameIdOffset, m.frame_id);
  put_u8(out, Odometry::kChildFrameIdOffset, m.child_frame_id);
  put_u8(out, Odometry::kResetCounterOffset, m.reset_counter);
  put_u8(out, Odometry::kEstimatorTypeOffset, m.estimator_type);
  put_u8(out, Odometry::kQualityOffset, static_cast<std::uint8_t>(m.quality));  // two's complement
}

void pack_payload(const VisionPositionDelta& m, std::span<std::uint8_t, VisionPositionDelta::kPayloadBytes> out) {
  put_u64(out, VisionPositionDelta::kTimeUsecOffset, m.time_usec);
  put_u64(out, VisionPositionDelta::kTimeDeltaUsecOffset, m.time_delta_usec);
  put_f32_array(out, VisionPositionDelta::kAngleDeltaOffset, m.angle_delta);
  put_f32_array(out, VisionPositionDelta::kPositionDeltaOffset, m.position_delta);
  put_f32(out, VisionPositionDelta::kConfidenceOffset, m.confidence);
}

void pack_payload(const SetGpsGlobalOrigin& m, std::span<std::uint8_t, SetGpsGlobalOrigin::kPayloadBytes> out) {
  put_u32(out, SetGpsGlobalOrigin::kLatitudeOffset, static_cast<std::uint32_t>(m.latitude_deg_e7));
  put_u32(out, SetGpsGlobalOrigin::kLongitudeOffset, static_cast<std::uint32_t>(m.longitude_deg_e7));
  put_u32(out, SetGpsGlobalOrigin::kAltitudeOffset, static_cast<std::uint32_t>(m.altitude_mm));
  put_u8(out, SetGpsGlobalOrigin::kTargetSystemOffset, m.target_system);
  put_u64(out, SetGpsGlobalOrigin::kTimeUsecOffset, m.time_usec);
}

void pack_payload(const SetHomePosition& m, std::span<std::uint8_t, SetHomePosition::kPayloadBytes> out) {
  put_u32(out, SetHomePosition::kLatitudeOffset, static_cast<std::uint32_t>(m.latitude_deg_e7));
  put_u32(out, SetHomePosition::kLongitudeOffset, static_cast<std::uint32_t>(m.longitude_deg_e7));
  put_u32(out, SetHomePosition::kAltitudeOffset, static_cast<std::uint32_t>(m.altitude_mm));
  put_f32(out, SetHomePosition::kXOffset, m.x);
  put_f32(out, SetHomePosition::kYOffset, m.y);
  put_f32(out, SetHomePosition::kZOffset, m.z);
  put_f32_array(out, SetHomePosition::kQOffset, m.q);
  put_f32(out, SetHomePosition::kApproachXOffset, m.approach_x);
  put_f32(out, SetHomePosition::kApproachYOffset, m.approach_y);
  put_f32(out, SetHomePosition::kApproachZOffset, m.approach_z);
  put_u8(out, SetHomePosition::kTargetSystemOffset, m.target_system);
  put_u64(out, SetHomePosition::kTimeUsecOffset, m.time_usec);
}

void pack_payload(const Attitude& m, std::span<std::uint8_t, Attitude::kPayloadBytes> out) {
  put_u32(out, Attitude::kTimeBootMsOffset, m.time_boot_ms);
  put_f32(out, Attitude::kRollOffset, m.roll);
  put_f32(out, Attitude::kPitchOffset, m.pitch);
  put_f32(out, Attitude::kYawOffset, m.yaw);
  put_f32(out, Attitude::kRollspeedOffset, m.rollspeed);
  put_f32(out, Attitude::kPitchspeedOffset, m.pitchspeed);
  put_f32(out, Attitude::kYawspeedOffset, m.yawspeed);
}

void pack_payload(const CommandLong& m, std::span<std::uint8_t, CommandLong::kPayloadBytes> out) {
  put_f32_array(out, CommandLong::kParamOffset, m.param);
  put_u16(out, CommandLong::kCommandOffset, m.command);
  put_u8(out, CommandLong::kTargetSystemOffset, m.target_system);
  put_u8(out, CommandLong::kTargetComponentOffset, m.target_component);
  put_u8(out, CommandLong::kConfirmationOffset, m.confirmation);
}

void pack_payload(const CommandAck& m, std::span<std::uint8_t, CommandAck::kPayloadBytes> out) {
  put_u16(out, CommandAck::kCommandOffset, m.command);
  put_u8(out, CommandAck::kResultOffset, m.result);
  put_u8(out, CommandAck::kProgressOffset, 0);
  put_u32(out, CommandAck::kResultParam2Offset, 0);
  put_u8(out, CommandAck::kTargetSystemOffset, m.target_system);
  put_u8(out, CommandAck::kTargetComponentOffset, m.target_component);
}

CommandAck unpack_command_ack(std::span<const std::uint8_t, kMaxPayloadBytes> payload) {
  CommandAck m;
  m.command = static_cast<std::uint16_t>(get_le(payload, CommandAck::kCommandOffset, 2));
  m.result = payload[CommandAck::kResultOffset];
  m.target_system = payload[CommandAck::kTargetSystemOffset];
  m.target_component = payload[CommandAck::kTargetComponentOffset];
  return m;
}

Attitude unpack_attitude(std::span<const std::uint8_t, kMaxPayloadBytes> payload) {
  const auto f32 = [&](std::size_t offset) {
    return std::bit_cast<float>(static_cast<std::uint32_t>(get_le(payload, offset, 4)));
  };
  Attitude m;
  m.time_boot_ms = static_cast<std::uint32_t>(get_le(payload, Attitude::kTimeBootMsOffset, 4));
  m.roll = f32(Attitude::kRollOffset);
  m.pitch = f32(Attitude::kPitchOffset);
  m.yaw = f32(Attitude::kYawOffset);
  m.rollspeed = f32(Attitude::kRollspeedOffset);
  m.pitchspeed = f32(Attitude::kPitchspeedOffset);
  m.yawspeed = f32(Attitude::kYawspeedOffset);
  return m;
}

std::optional<std::uint8_t> sent_crc_extra(std::uint32_t msgid) {
  switch (msgid) {
    case Heartbeat::kId: return Heartbeat::kCrcExtra;
    case Timesync::kId: return Timesync::kCrcExtra;
    case Odometry::kId: return Odometry::kCrcExtra;
    case VisionPositionDelta::kId: return VisionPositionDelta::kCrcExtra;
    case SetGpsGlobalOrigin::kId: return SetGpsGlobalOrigin::kCrcExtra;
    case SetHomePosition::kId: return SetHomePosition::kCrcExtra;
    case CommandLong::kId: return CommandLong::kCrcExtra;
    default: return std::nullopt;
  }
}

bool restamp_sequence(std::span<std::uint8_t> frame, std::uint8_t sequence) {
  if (frame.size() < kHeaderBytes + kChecksumBytes || frame[0] != kMagicV2 || frame[2] != 0) return false;
  const std::size_t crc_at = kHeaderBytes + frame[1];
  if (frame.size() != crc_at + kChecksumBytes) return false;
  const auto msgid = static_cast<std::uint32_t>(frame[7] | frame[8] << 8 | frame[9] << 16);
  const std::optional<std::uint8_t> crc_extra = sent_crc_extra(msgid);
  if (!crc_extra) return false;
  frame[4] = sequence;
  std::uint16_t crc = crc16_mcrf4xx(frame.subspan(1, crc_at - 1));
  crc = crc_accumulate(*crc_extra, crc);
  frame[crc_at] = static_cast<std::uint8_t>(crc & 0xFF);
  frame[crc_at + 1] = static_cast<std::uint8_t>(crc >> 8);
  return true;
}

std::size_t trimmed_length(std::span<const std::uint8_t> payload) {
  std::size_t n = payload.size();
  while (n > 1 && payload[n - 1] == 0) --n;
  return n;
}

std::size_t Framer::finish_frame(std::uint32_t message_id, std::uint8_t crc_extra, std::size_t payload_bytes,
                                 FrameSpan out) {
  const auto payload_len = static_cast<std::uint8_t>(trimmed_length(out.subspan(kHeaderBytes, payload_bytes)));
  out[0] = kMagicV2;
  out[1] = payload_len;
  out[2] = 0;  // incompat_flags: no signing
  out[3] = 0;  // compat_flags
  out[4] = sequence_++;  // uint8 arithmetic: wraps 255 -> 0
  out[5] = system_id_;
  out[6] = component_id_;
  out[7] = static_cast<std::uint8_t>(message_id);
  out[8] = static_cast<std::uint8_t>(message_id >> 8);
  out[9] = static_cast<std::uint8_t>(message_id >> 16);
  const std::size_t crc_at = kHeaderBytes + payload_len;
  std::uint16_t crc = crc16_mcrf4xx(std::span<const std::uint8_t>(out.data() + 1, crc_at - 1));
  crc = crc_accumulate(crc_extra, crc);
  out[crc_at] = static_cast<std::uint8_t>(crc & 0xFF);
  out[crc_at + 1] = static_cast<std::uint8_t>(crc >> 8);
  return crc_at + kChecksumBytes;
}

template <typename Message>
std::size_t Framer::encode_message(const Message& m, FrameSpan out) {
  pack_payload(m, payload_area<Message>(out));
  return finish_frame(Message::kId, Message::kCrcExtra, Message::kPayloadBytes, out);
}

std::size_t Framer::encode(const Heartbeat& m, FrameSpan out) { return encode_message(m, out); }
std::size_t Framer::encode(const Timesync& m, FrameSpan out) { return encode_message(m, out); }
std::size_t Framer::encode(const Odometry& m, FrameSpan out) { return encode_message(m, out); }
std::size_t Framer::encode(const VisionPositionDelta& m, FrameSpan out) { return encode_message(m, out); }
std::size_t Framer::encode(const SetGpsGlobalOrigin& m, FrameSpan out) { return encode_message(m, out); }
std::size_t Framer::encode(const SetHomePosition& m, FrameSpan out) { return encode_message(m, out); }
std::size_t Framer::encode(const Attitude& m, FrameSpan out) { return encode_message(m, out); }
std::size_t Framer::encode(const CommandLong& m, FrameSpan out) { return encode_message(m, out); }
std::size_t Framer::encode(const CommandAck& m, FrameSpan out) { return encode_message(m, out); }

}  // namespace rgbdo::mavlink
