#pragma once
// The wire to the flight computer: MAVLink 2 frames, written by hand so that the product
// carries no generated MAVLink library. The messages it needs only: HEARTBEAT
// (common.xml/minimal.xml), TIMESYNC, ODOMETRY, SET_GPS_GLOBAL_ORIGIN, SET_HOME_POSITION
// (common.xml) and VISION_POSITION_DELTA (ardupilotmega.xml). Received frames are split and
// checked by mavlink_parser.hpp; HEARTBEAT, TIMESYNC, ATTITUDE and COMMAND_ACK are also read
// here. COMMAND_LONG carries our one command: MAV_CMD_SET_MESSAGE_INTERVAL.
//
// Frame (MAVLink 2, unsigned):
//   0xFD | len | incompat_flags=0 | compat_flags=0 | seq | sysid | compid | msgid (3 B, LE)
//   | payload (len bytes) | crc (2 B, LE)
// The payload is the message's fields in wire order (base fields sorted by element size,
// largest first, stable; extension fields after them in XML order), little-endian, with
// trailing zero bytes trimmed (the receiver zero-fills them again); at least one byte stays.
// The CRC is CRC-16/MCRF4XX over len..end of payload, then over the message's CRC_EXTRA byte,
// which a receiver uses to reject a message whose definition differs from its own.
//
// Every constant below was checked against the published definitions (mavlink/mavlink
// message_definitions, the generated mavlink/c_library_v2 headers); test_mavlink.cpp derives
// each CRC_EXTRA again from the field list.
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>

namespace rgbdo::mavlink {

// ---- frame layout ---------------------------------------------------------------------
inline constexpr std::uint8_t kMagicV2 = 0xFD;
inline constexpr std::uint8_t kMagicV1 = 0xFE;  // received only: autopilots still emit it on some ports
inline constexpr std::uint8_t kIncompatFlagSigned = 0x01;  // a 13-byte signature follows the checksum
inline constexpr std::size_t kHeaderBytes = 10;     // magic .. msgid
inline constexpr std::size_t kChecksumBytes = 2;
inline constexpr std::size_t kSignatureBytes = 13;  // never written (no signing), but a
                                                    // buffer that can hold any frame is the
                                                    // size every MAVLink 2 implementation uses
inline constexpr std::size_t kMaxPayloadBytes = 255;
inline constexpr std::size_t kMaxFrameBytes = kHeaderBytes + kMaxPayloadBytes + kChecksumBytes + kSignatureBytes;
static_assert(kMaxFrameBytes == 280);

using FrameBuffer = std::array<std::uint8_t, kMaxFrameBytes>;
using FrameSpan = std::span<std::uint8_t, kMaxFrameBytes>;  // a FrameBuffer converts implicitly

// ---- enum values used by this program (common.xml / minimal.xml) -----------------------
inline constexpr std::uint8_t kMavTypeOnboardController = 18;           // MAV_TYPE
inline constexpr std::uint8_t kMavAutopilotInvalid = 8;                 // MAV_AUTOPILOT: not an autopilot
inline constexpr std::uint8_t kMavAutopilotArdupilotmega = 3;
inline constexpr std::uint8_t kMavAutopilotPx4 = 12;
inline constexpr std::uint8_t kMavStateStandby = 3;                     // MAV_STATE
inline constexpr std::uint8_t kMavStateActive = 4;
inline constexpr std::uint8_t kMavStateCritical = 5;
inline constexpr std::uint8_t kMavCompIdVisualInertialOdometry = 197;  // MAV_COMPONENT
inline constexpr std::uint8_t kMavFrameBodyFrd = 12;                    // MAV_FRAME
inline constexpr std::uint8_t kMavFrameLocalFrd = 20;
inline constexpr std::uint8_t kMavEstimatorTypeVision = 2;  // MAV_ESTIMATOR_TYPE (3 is VIO)
inline constexpr std::uint8_t kMavlinkVersion = 3;          // HEARTBEAT.mavlink_version

inline constexpr float kUnknown = std::numeric_limits<float>::quiet_NaN();

// ---- messages ---------------------------------------------------------------------------
// Field comments give unit and invalid value; `k*Offset` is the byte offset in the payload.

struct Heartbeat {  // #0
  static constexpr std::uint32_t kId = 0;
  static constexpr std::uint8_t kCrcExtra = 50;
  static constexpr std::size_t kPayloadBytes = 9;

  std::uint32_t custom_mode = 0;
  std::uint8_t type = kMavTypeOnboardController;
  std::uint8_t autopilot = kMavAutopilotInvalid;
  std::uint8_t base_mode = 0;
  std::uint8_t system_status = kMavStateStandby;
  std::uint8_t mavlink_version = kMavlinkVersion;

  static constexpr std::size_t kCustomModeOffset = 0, kTypeOffset = 4, kAutopilotOffset = 5, kBaseModeOffset = 6,
                               kSystemStatusOffset = 7, kMavlinkVersionOffset = 8;
};
static_assert(Heartbeat::kMavlinkVersionOffset + 1 == Heartbeat::kPayloadBytes);

struct Timesync {  // #111, common.xml (time synchronisation protocol v2)
  static constexpr std::uint32_t kId = 111;
  static constexpr std::uint8_t kCrcExtra = 34;
  static constexpr std::size_t kBasePayloadBytes = 16;  // tc1, ts1 (what v1 senders send)
  static constexpr std::size_t kPayloadBytes = 18;

  // [ns] 0 in a request; in a response, the responder's clock when it answered.
  std::int64_t tc1 = 0;
  // [ns] the requester's clock when it asked; a response echoes it unchanged.
  std::int64_t ts1 = 0;
  // Extensions: in a response, the requester's ids (0: broadcast, a v1 responder); in a
  // request, whom it asks (0: anyone).
  std::uint8_t target_system = 0;
  std::uint8_t target_component = 0;

  static constexpr std::size_t kTc1Offset = 0, kTs1Offset = 8, kTargetSystemOffset = 16, kTargetComponentOffset = 17;
};
static_assert(Timesync::kTargetComponentOffset + 1 == Timesync::kPayloadBytes);

struct Odometry {  // #331, common.xml
  static constexpr std::uint32_t kId = 331;
  static constexpr std::uint8_t kCrcExtra = 91;
  static constexpr std::size_t kBasePayloadBytes = 230;  // without the extension fields
  static constexpr std::size_t kPayloadBytes = 233;

  std::uint64_t time_usec = 0;                 // [us] capture time of the pose
  std::uint8_t frame_id = kMavFrameLocalFrd;   // frame of the pose
  std::uint8_t child_frame_id = kMavFrameBodyFrd;  // frame of the velocities
  float x = 0, y = 0, z = 0;                   // [m] position in frame_id
  std::array<float, 4> q{1, 0, 0, 0};          // w, x, y, z: rotation child (body) -> frame_id
  float vx = kUnknown, vy = kUnknown, vz = kUnknown;  // [m/s] in child_frame_id, NaN unknown
  float rollspeed = kUnknown, pitchspeed = kUnknown, yawspeed = kUnknown;  // [rad/s], NaN unknown
  // Upper triangle, row-major, of the 6x6 covariance of (x, y, z, roll, pitch, yaw), [m^2,
  // rad^2, m rad]; NaN in the first element means unknown.
  std::array<float, 21> pose_covariance = unknown_covariance();
  // Same, of (vx, vy, vz, rollspeed, pitchspeed, yawspeed).
  std::array<float, 21> velocity_covariance = unknown_covariance();
  // Extensions.
  std::uint8_t reset_counter = 0;  // incremented when the estimate jumps
  std::uint8_t estimator_type = kMavEstimatorTypeVision;
  std::int8_t quality = 0;  // [%] -1 failed, 0 unknown, 1 worst .. 100 best

  static constexpr std::array<float, 21> unknown_covariance() {
    std::array<float, 21> c{};
    c.fill(kUnknown);
    return c;
  }

  static constexpr std::size_t kTimeUsecOffset = 0, kXOffset = 8, kYOffset = 12, kZOffset = 16, kQOffset = 20,
                               kVxOffset = 36, kVyOffset = 40, kVzOffset = 44, kRollspeedOffset = 48,
                               kPitchspeedOffset = 52, kYawspeedOffset = 56, kPoseCovarianceOffset = 60,
                               kVelocityCovarianceOffset = 144, kFrameIdOffset = 228, kChildFrameIdOffset = 229,
                               kResetCounterOffset = 230, kEstimatorTypeOffset = 231, kQualityOffset = 232;
};
static_assert(Odometry::kQOffset + 4 * 4 == Odometry::kVxOffset);
static_assert(Odometry::kPoseCovarianceOffset + 21 * 4 == Odometry::kVelocityCovarianceOffset);
static_assert(Odometry::kVelocityCovarianceOffset + 21 * 4 == Odometry::kFrameIdOffset);
static_assert(Odometry::kChildFrameIdOffset + 1 == Odometry::kBasePayloadBytes);
static_assert(Odometry::kQualityOffset + 1 == Odometry::kPayloadBytes);

struct VisionPositionDelta {  // #11011, ardupilotmega.xml
  static constexpr std::uint32_t kId = 11011;
  static constexpr std::uint8_t kCrcExtra = 106;
  static constexpr std::size_t kPayloadBytes = 44;

  std::uint64_t time_usec = 0;        // [us] capture time of the current frame
  std::uint64_t time_delta_usec = 0;  // [us] since the previous frame
  // [rad] rotation vector from the previous body frame to the current one.
  std::array<float, 3> angle_delta{0, 0, 0};
  // [m] position change, expressed in the current body frame ("rotated to the current
  // MAV_FRAME_BODY_FRD" in the definition).
  std::array<float, 3> position_delta{0, 0, 0};
  float confidence = 0;  // [%] 0..100

  static constexpr std::size_t kTimeUsecOffset = 0, kTimeDeltaUsecOffset = 8, kAngleDeltaOffset = 16,
                               kPositionDeltaOffset = 28, kConfidenceOffset = 40;
};
static_assert(VisionPositionDelta::kConfidenceOffset + 4 == VisionPositionDelta::kPayloadBytes);

struct SetGpsGlobalOrigin {  // #48, common.xml: ArduPilot's EKF3 needs an origin to use a position without GPS
  static constexpr std::uint32_t kId = 48;
  static constexpr std::uint8_t kCrcExtra = 41;
  static constexpr std::size_t kPayloadBytes = 21;

  std::int32_t latitude_deg_e7 = 0;   // [degE7] WGS84
  std::int32_t longitude_deg_e7 = 0;  // [degE7]
  std::int32_t altitude_mm = 0;       // [mm] AMSL, positive up
  std::uint8_t target_system = 0;
  std::uint64_t time_usec = 0;  // extension: [us] 0 = unknown

  static constexpr std::size_t kLatitudeOffset = 0, kLongitudeOffset = 4, kAltitudeOffset = 8,
                               kTargetSystemOffset = 12, kTimeUsecOffset = 13;
};
static_assert(SetGpsGlobalOrigin::kTimeUsecOffset + 8 == SetGpsGlobalOrigin::kPayloadBytes);

struct SetHomePosition {  // #243, common.xml: home at the origin, so that RTL has a place to go
  static constexpr std::uint32_t kId = 243;
  static constexpr std::uint8_t kCrcExtra = 85;
  static constexpr std::size_t kPayloadBytes = 61;

  std::int32_t latitude_deg_e7 = 0;   // [degE7]
  std::int32_t longitude_deg_e7 = 0;  // [degE7]
  std::int32_t altitude_mm = 0;       // [mm] AMSL
  float x = 0, y = 0, z = 0;          // [m] home in the local frame
  std::array<float, 4> q{1, 0, 0, 0};  // w, x, y, z: the surface's orientation (level)
  float approach_x = 0, approach_y = 0, approach_z = 0;  // [m]
  std::uint8_t target_system = 0;
  std::uint64_t time_usec = 0;  // extension: [us] 0 = unknown

  static constexpr std::size_t kLatitudeOffset = 0, kLongitudeOffset = 4, kAltitudeOffset = 8, kXOffset = 12,
                               kYOffset = 16, kZOffset = 20, kQOffset = 24, kApproachXOffset = 40,
                               kApproachYOffset = 44, kApproachZOffset = 48, kTargetSystemOffset = 52,
                               kTimeUsecOffset = 53;
};
static_assert(SetHomePosition::kTimeUsecOffset + 8 == SetHomePosition::kPayloadBytes);


struct Attitude {  // #30, common.xml: received only, to level the local frame at the first pair
  static constexpr std::uint32_t kId = 30;
  static constexpr std::uint8_t kCrcExtra = 39;
  static constexpr std::size_t kPayloadBytes = 28;

  std::uint32_t time_boot_ms = 0;  // [ms] the autopilot's clock
  float roll = 0, pitch = 0, yaw = 0;  // [rad] the FRD body in the autopilot's NED frame
  float rollspeed = 0, pitchspeed = 0, yawspeed = 0;  // [rad/s]

  static constexpr std::size_t kTimeBootMsOffset = 0, kRollOffset = 4, kPitchOffset = 8, kYawOffset = 12,
                               kRollspeedOffset = 16, kPitchspeedOffset = 20, kYawspeedOffset = 24;
};
static_assert(Attitude::kYawspeedOffset + 4 == Attitude::kPayloadBytes);

inline constexpr std::uint16_t kMavCmdSetMessageInterval = 511;  // MAV_CMD
inline constexpr std::uint8_t kMavResultAccepted = 0;             // MAV_RESULT

struct CommandLong {  // #76, common.xml: sent to ask for the autopilot's ATTITUDE at our rate
  static constexpr std::uint32_t kId = 76;
  static constexpr std::uint8_t kCrcExtra = 152;
  static constexpr std::size_t kPayloadBytes = 33;

  std::array<float, 7> param{0, 0, 0, 0, 0, 0, 0};  // param1 .. param7
  std::uint16_t command = 0;                         // MAV_CMD
  std::uint8_t target_system = 0, target_component = 0;
  std::uint8_t confirmation = 0;  // 0 the first time, +1 for each repeat

  static constexpr std::size_t kParamOffset = 0, kCommandOffset = 28, kTargetSystemOffset = 30,
                               kTargetComponentOffset = 31, kConfirmationOffset = 32;
};
static_assert(CommandLong::kConfirmationOffset + 1 == CommandLong::kPayloadBytes);

struct CommandAck {  // #77, common.xml: received, the autopilot's verdict on a command of ours
  static constexpr std::uint32_t kId = 77;
  static constexpr std::uint8_t kCrcExtra = 143;
  static constexpr std::size_t kPayloadBytes = 10;  // with the extensions

  std::uint16_t command = 0;
  std::uint8_t result = 0;  // MAV_RESULT
  // Extensions: progress, result_param2, and whom the answer is for.
  std::uint8_t target_system = 0, target_component = 0;

  static constexpr std::size_t kCommandOffset = 0, kResultOffset = 2, kProgressOffset = 3, kResultParam2Offset = 4,
                               kTargetSystemOffset = 8, kTargetComponentOffset = 9;
};
static_assert(CommandAck::kTargetComponentOffset + 1 == CommandAck::kPayloadBytes);

// ---- payloads: the full, untrimmed wire image of one message ---------------------------
void pack_payload(const Heartbeat& m, std::span<std::uint8_t, Heartbeat::kPayloadBytes> out);
void pack_payload(const Timesync& m, std::span<std::uint8_t, Timesync::kPayloadBytes> out);
void pack_payload(const Odometry& m, std::span<std::uint8_t, Odometry::kPayloadBytes> out);
void pack_payload(const VisionPositionDelta& m, std::span<std::uint8_t, VisionPositionDelta::kPayloadBytes> out);
void pack_payload(const SetGpsGlobalOrigin& m, std::span<std::uint8_t, SetGpsGlobalOrigin::kPayloadBytes> out);
void pack_payload(const SetHomePosition& m, std::span<std::uint8_t, SetHomePosition::kPayloadBytes> out);
void pack_payload(const Attitude& m, std::span<std::uint8_t, Attitude::kPayloadBytes> out);  // tests send it
void pack_payload(const CommandLong& m, std::span<std::uint8_t, CommandLong::kPayloadBytes> out);
void pack_payload(const CommandAck& m, std::span<std::uint8_t, CommandAck::kPayloadBytes> out);  // tests send it

// The received messages, from a payload already zero-extended to at least the message's full
// length (mavlink_parser.hpp hands out kMaxPayloadBytes).
[[nodiscard]] Heartbeat unpack_heartbeat(std::span<const std::uint8_t, kMaxPayloadBytes> payload);
[[nodiscard]] Timesync unpack_timesync(std::span<const std::uint8_t, kMaxPayloadBytes> payload);
[[nodiscard]] Attitude unpack_attitude(std::span<const std::uint8_t, kMaxPayloadBytes> payload);
[[nodiscard]] CommandAck unpack_command_ack(std::span<const std::uint8_t, kMaxPayloadBytes> payload);

// ---- checksum ---------------------------------------------------------------------------
inline constexpr std::uint16_t kCrcInit = 0xFFFF;
// CRC-16/MCRF4XX (the "X.25" CRC of MAVLink): reflected polynomial 0x1021, no final XOR.
[[nodiscard]] constexpr std::uint16_t crc_accumulate(std::uint8_t byte, std::uint16_t crc) {
  // The byte-wise form MAVLink's checksum.h uses: no table, 8 shifts folded into 4.
  std::uint8_t tmp = byte ^ static_cast<std::uint8_t>(crc & 0xFF);
  tmp = static_cast<std::uint8_t>(tmp ^ (tmp << 4));
  return static_cast<std::uint16_t>((crc >> 8) ^ (tmp << 8) ^ (tmp << 3) ^ (tmp >> 4));
}
[[nodiscard]] constexpr std::uint16_t crc16_mcrf4xx(std::span<const std::uint8_t> bytes, std::uint16_t crc = kCrcInit) {
  for (const std::uint8_t b : bytes) crc = crc_accumulate(b, crc);
  return crc;
}

// ---- framing ----------------------------------------------------------------------------
// One framer per link: the sequence number counts this link's frames (receivers use it to
// count losses), starting at 0 and wrapping after 255.
class Framer {
 public:
  Framer(std::uint8_t system_id, std::uint8_t component_id) : system_id_(system_id), component_id_(component_id) {}

  // Write one complete frame at the start of `out`; returns its length in bytes.
  [[nodiscard]] std::size_t encode(const Heartbeat& m, FrameSpan out);
  [[nodiscard]] std::size_t encode(const Timesync& m, FrameSpan out);
  [[nodiscard]] std::size_t encode(const Odometry& m, FrameSpan out);
  [[nodiscard]] std::size_t encode(const VisionPositionDelta& m, FrameSpan out);
  [[nodiscard]] std::size_t encode(const SetGpsGlobalOrigin& m, FrameSpan out);
  [[nodiscard]] std::size_t encode(const SetHomePosition& m, FrameSpan out);
  [[nodiscard]] std::size_t encode(const Attitude& m, FrameSpan out);  // tests send it
  [[nodiscard]] std::size_t encode(const CommandLong& m, FrameSpan out);
  [[nodiscard]] std::size_t encode(const CommandAck& m, FrameSpan out);  // tests send it

  // The framing alone, for a payload of `payload_bytes` already written at out[kHeaderBytes]:
  // trims its trailing zeros, writes header and checksum, returns the frame length.
  // payload_bytes must not exceed kMaxPayloadBytes.
  [[nodiscard]] std::size_t finish_frame(std::uint32_t message_id, std::uint8_t crc_extra, std::size_t payload_bytes,
                                         FrameSpan out);

  std::uint8_t next_sequence() const { return sequence_; }

 private:
  template <typename Message>
  std::size_t encode_message(const Message& m, FrameSpan out);

  std::uint8_t system_id_;
  std::uint8_t component_id_;
  std::uint8_t sequence_ = 0;
};

// CRC_EXTRA of the messages this program sends; nullopt for any other id.
[[nodiscard]] std::optional<std::uint8_t> sent_crc_extra(std::uint32_t msgid);

// Gives an encoded frame of ours (unsigned MAVLink 2) another sequence number and its
// checksum again: a transport that sends some frames ahead of others numbers them in wire
// order, so that receivers counting losses by the sequence count none. False (frame
// untouched) when it is not a frame of a message we send.
bool restamp_sequence(std::span<std::uint8_t> frame, std::uint8_t sequence);

// Length of a payload after MAVLink 2 trimming: trailing zero bytes dropped, never below 1.
[[nodiscard]] std::size_t trimmed_length(std::span<const std::uint8_t> payload);

}  // namespace rgbdo::mavlink
