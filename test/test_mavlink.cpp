// The MAVLink 2 wire: golden bytes, the checksum, trimming, sequence numbers, and each field
// at the offset the published definitions imply. Everything here is derived independently
// of src/link/mavlink.cpp: a bit-serial CRC, a wire order computed from the XML field lists, and
// a decoder that zero-fills trimmed payloads as a receiver does.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include "rgbd_odometry/link/mavlink.hpp"
#include "mavlink_reference.hpp"

namespace rgbdo::mavlink {
namespace {

using namespace mavlink_reference;

// ---- independent references: mavlink_reference.hpp ---------------------------------

// minimal.xml / common.xml (HEARTBEAT), common.xml (ODOMETRY), ardupilotmega.xml
// (VISION_POSITION_DELTA), in XML order.
const std::vector<XmlField> kHeartbeatXml = {{"uint8_t", "type"},      {"uint8_t", "autopilot"},
                                             {"uint8_t", "base_mode"}, {"uint32_t", "custom_mode"},
                                             {"uint8_t", "system_status"}, {"uint8_t", "mavlink_version"}};
const std::vector<XmlField> kOdometryXml = {
    {"uint64_t", "time_usec"},   {"uint8_t", "frame_id"},        {"uint8_t", "child_frame_id"},
    {"float", "x"},              {"float", "y"},                 {"float", "z"},
    {"float", "q", 4},           {"float", "vx"},                {"float", "vy"},
    {"float", "vz"},             {"float", "rollspeed"},         {"float", "pitchspeed"},
    {"float", "yawspeed"},       {"float", "pose_covariance", 21}, {"float", "velocity_covariance", 21},
    {"uint8_t", "reset_counter", 0, true}, {"uint8_t", "estimator_type", 0, true}, {"int8_t", "quality", 0, true}};
const std::vector<XmlField> kVisionPositionDeltaXml = {{"uint64_t", "time_usec"},
                                                       {"uint64_t", "time_delta_usec"},
                                                       {"float", "angle_delta", 3},
                                                       {"float", "position_delta", 3},
                                                       {"float", "confidence"}};
const std::vector<XmlField> kCommandLongXml = {{"uint8_t", "target_system"}, {"uint8_t", "target_component"},
                                               {"uint16_t", "command"},      {"uint8_t", "confirmation"},
                                               {"float", "param1"},          {"float", "param2"},
                                               {"float", "param3"},          {"float", "param4"},
                                               {"float", "param5"},          {"float", "param6"},
                                               {"float", "param7"}};

// Little-endian reads by shifting, so the test holds on any host.
std::uint64_t read_le(const std::uint8_t* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}
float read_f32(const std::vector<std::uint8_t>& payload, std::size_t offset) {
  return std::bit_cast<float>(static_cast<std::uint32_t>(read_le(payload.data() + offset, 4)));
}

// A receiver: checks the frame and returns the payload zero-filled to `full_length`.
struct Decoded {
  std::uint8_t seq = 0, sysid = 0, compid = 0;
  std::uint32_t msgid = 0;
  std::vector<std::uint8_t> payload;
};
Decoded decode(const FrameBuffer& frame, std::size_t frame_length, std::uint8_t crc_extra, std::size_t full_length) {
  Decoded d;
  EXPECT_EQ(frame[0], 0xFD);
  const std::size_t len = frame[1];
  EXPECT_EQ(frame_length, 10 + len + 2);
  EXPECT_EQ(frame[2], 0) << "incompat_flags";
  EXPECT_EQ(frame[3], 0) << "compat_flags";
  d.seq = frame[4];
  d.sysid = frame[5];
  d.compid = frame[6];
  d.msgid = static_cast<std::uint32_t>(read_le(&frame[7], 3));
  std::uint16_t crc = reference_crc(&frame[1], 9 + len);
  crc = reference_crc(&crc_extra, 1, crc);
  EXPECT_EQ(read_le(&frame[10 + len], 2), crc) << "checksum";
  d.payload.assign(frame.begin() + 10, frame.begin() + 10 + static_cast<std::ptrdiff_t>(len));
  EXPECT_GE(len, 1u);
  EXPECT_TRUE(len == 1 || d.payload.back() != 0) << "a trailing zero was not trimmed";
  d.payload.resize(full_length, 0);
  return d;
}

// ---- tests ------------------------------------------------------------------------------

TEST(MavlinkCrc, CheckValueOfCrc16Mcrf4xx) {
  // The catalogue check value of CRC-16/MCRF4XX: CRC of ASCII "123456789".
  constexpr std::string_view check = "123456789";
  const auto* bytes = reinterpret_cast<const std::uint8_t*>(check.data());
  EXPECT_EQ(crc16_mcrf4xx({bytes, check.size()}), 0x6F91);
  EXPECT_EQ(reference_crc(bytes, check.size()), 0x6F91);
  static_assert(crc16_mcrf4xx(std::array<std::uint8_t, 9>{'1', '2', '3', '4', '5', '6', '7', '8', '9'}) == 0x6F91);
}

TEST(MavlinkCrc, ByteWiseFormEqualsBitSerialOnEveryByteAndState) {
  for (std::uint32_t state = 0; state <= 0xFFFF; state += 257)
    for (std::uint32_t byte = 0; byte <= 0xFF; ++byte) {
      const auto b = static_cast<std::uint8_t>(byte);
      ASSERT_EQ(crc_accumulate(b, static_cast<std::uint16_t>(state)),
                reference_crc(&b, 1, static_cast<std::uint16_t>(state)));
    }
}

TEST(MavlinkDefinitions, CrcExtraDerivedFromFieldListsEqualsConstants) {
  EXPECT_EQ(derive_crc_extra("HEARTBEAT", kHeartbeatXml), Heartbeat::kCrcExtra);
  EXPECT_EQ(derive_crc_extra("ODOMETRY", kOdometryXml), Odometry::kCrcExtra);
  EXPECT_EQ(derive_crc_extra("VISION_POSITION_DELTA", kVisionPositionDeltaXml), VisionPositionDelta::kCrcExtra);
  EXPECT_EQ(derive_crc_extra("COMMAND_LONG", kCommandLongXml), CommandLong::kCrcExtra);
  // The values the generated headers carry (MAVLINK_MSG_ID_*_CRC), as a check of the check.
  EXPECT_EQ(Heartbeat::kCrcExtra, 50);
  EXPECT_EQ(Odometry::kCrcExtra, 91);
  EXPECT_EQ(VisionPositionDelta::kCrcExtra, 106);
  // Extension fields must not enter CRC_EXTRA: ODOMETRY gained three without changing it.
  std::vector<XmlField> odometry_v1(kOdometryXml.begin(), kOdometryXml.end() - 3);
  EXPECT_EQ(derive_crc_extra("ODOMETRY", odometry_v1), 91);
}

TEST(MavlinkDefinitions, MessageIdsAndLengths) {
  EXPECT_EQ(Heartbeat::kId, 0u);
  EXPECT_EQ(Odometry::kId, 331u);
  EXPECT_EQ(VisionPositionDelta::kId, 11011u);
  EXPECT_EQ(wire_length(kHeartbeatXml, true), Heartbeat::kPayloadBytes);
  EXPECT_EQ(wire_length(kOdometryXml, false), Odometry::kBasePayloadBytes);
  EXPECT_EQ(wire_length(kOdometryXml, true), Odometry::kPayloadBytes);
  EXPECT_EQ(wire_length(kVisionPositionDeltaXml, true), VisionPositionDelta::kPayloadBytes);
  EXPECT_EQ(wire_length(kCommandLongXml, true), CommandLong::kPayloadBytes);
  EXPECT_EQ(wire_offset(kCommandLongXml, "command"), CommandLong::kCommandOffset);
  EXPECT_EQ(wire_offset(kCommandLongXml, "target_component"), CommandLong::kTargetComponentOffset);
  EXPECT_EQ(wire_offset(kCommandLongXml, "confirmation"), CommandLong::kConfirmationOffset);
  EXPECT_EQ(Odometry::kBasePayloadBytes, 230u);
  EXPECT_EQ(Odometry::kPayloadBytes, 233u);
  EXPECT_EQ(VisionPositionDelta::kPayloadBytes, 44u);
}

TEST(MavlinkDefinitions, HeaderOffsetsAreTheWireOrderOfTheXml) {
  const auto& H = kHeartbeatXml;
  EXPECT_EQ(wire_offset(H, "custom_mode"), Heartbeat::kCustomModeOffset);
  EXPECT_EQ(wire_offset(H, "type"), Heartbeat::kTypeOffset);
  EXPECT_EQ(wire_offset(H, "autopilot"), Heartbeat::kAutopilotOffset);
  EXPECT_EQ(wire_offset(H, "base_mode"), Heartbeat::kBaseModeOffset);
  EXPECT_EQ(wire_offset(H, "system_status"), Heartbeat::kSystemStatusOffset);
  EXPECT_EQ(wire_offset(H, "mavlink_version"), Heartbeat::kMavlinkVersionOffset);
  const auto& O = kOdometryXml;
  EXPECT_EQ(wire_offset(O, "time_usec"), Odometry::kTimeUsecOffset);
  EXPECT_EQ(wire_offset(O, "x"), Odometry::kXOffset);
  EXPECT_EQ(wire_offset(O, "y"), Odometry::kYOffset);
  EXPECT_EQ(wire_offset(O, "z"), Odometry::kZOffset);
  EXPECT_EQ(wire_offset(O, "q"), Odometry::kQOffset);
  EXPECT_EQ(wire_offset(O, "vx"), Odometry::kVxOffset);
  EXPECT_EQ(wire_offset(O, "vy"), Odometry::kVyOffset);
  EXPECT_EQ(wire_offset(O, "vz"), Odometry::kVzOffset);
  EXPECT_EQ(wire_offset(O, "rollspeed"), Odometry::kRollspeedOffset);
  EXPECT_EQ(wire_offset(O, "pitchspeed"), Odometry::kPitchspeedOffset);
  EXPECT_EQ(wire_offset(O, "yawspeed"), Odometry::kYawspeedOffset);
  EXPECT_EQ(wire_offset(O, "pose_covariance"), Odometry::kPoseCovarianceOffset);
  EXPECT_EQ(wire_offset(O, "velocity_covariance"), Odometry::kVelocityCovarianceOffset);
  EXPECT_EQ(wire_offset(O, "frame_id"), Odometry::kFrameIdOffset);
  EXPECT_EQ(wire_offset(O, "child_frame_id"), Odometry::kChildFrameIdOffset);
  EXPECT_EQ(wire_offset(O, "reset_counter"), Odometry::kResetCounterOffset);
  EXPECT_EQ(wire_offset(O, "estimator_type"), Odometry::kEstimatorTypeOffset);
  EXPECT_EQ(wire_offset(O, "quality"), Odometry::kQualityOffset);
  const auto& V = kVisionPositionDeltaXml;
  EXPECT_EQ(wire_offset(V, "time_usec"), VisionPositionDelta::kTimeUsecOffset);
  EXPECT_EQ(wire_offset(V, "time_delta_usec"), VisionPositionDelta::kTimeDeltaUsecOffset);
  EXPECT_EQ(wire_offset(V, "angle_delta"), VisionPositionDelta::kAngleDeltaOffset);
  EXPECT_EQ(wire_offset(V, "position_delta"), VisionPositionDelta::kPositionDeltaOffset);
  EXPECT_EQ(wire_offset(V, "confidence"), VisionPositionDelta::kConfidenceOffset);
}

TEST(MavlinkFraming, HeartbeatGoldenBytes) {
  // GIVEN the heartbeat this program sends before its first pair, from system 1, component
  // 197 (MAV_COMP_ID_VISUAL_INERTIAL_ODOMETRY)
  Framer framer(1, kMavCompIdVisualInertialOdometry);
  Heartbeat hb;  // onboard controller, no autopilot, base_mode 0, custom_mode 0, STANDBY
  FrameBuffer frame{};
  // WHEN it is framed twice, the second time ACTIVE
  const std::size_t n0 = framer.encode(hb, frame);
  const std::vector<std::uint8_t> first(frame.begin(), frame.begin() + static_cast<std::ptrdiff_t>(n0));
  hb.system_status = kMavStateActive;
  const std::size_t n1 = framer.encode(hb, frame);
  const std::vector<std::uint8_t> second(frame.begin(), frame.begin() + static_cast<std::ptrdiff_t>(n1));
  // THEN the bytes are, by hand from the definition:
  const std::vector<std::uint8_t> expected_first = {
      0xFD,              // MAVLink 2 magic
      0x09,              // payload length: 9, the last byte (mavlink_version 3) is not zero
      0x00, 0x00,        // incompat_flags, compat_flags
      0x00,              // seq: first frame of this framer
      0x01, 0xC5,        // sysid 1, compid 197
      0x00, 0x00, 0x00,  // msgid 0, 24-bit little-endian
      0x00, 0x00, 0x00, 0x00,  // custom_mode (uint32 first: wire order sorts by size)
      0x12,              // type: MAV_TYPE_ONBOARD_CONTROLLER 18
      0x08,              // autopilot: MAV_AUTOPILOT_INVALID 8
      0x00,              // base_mode
      0x03,              // system_status: MAV_STATE_STANDBY 3
      0x03,              // mavlink_version 3
      // CRC-16/MCRF4XX of bytes 1..18 then of CRC_EXTRA 50, low byte first: 0x681B
      // (computed with the bit-serial reference above and, separately, with pymavlink's
      // x25crc algorithm by hand in Python).
      0x1B, 0x68};
  EXPECT_EQ(first, expected_first);
  const std::vector<std::uint8_t> expected_second = {0xFD, 0x09, 0x00, 0x00,
                                                     0x01,  // seq 1
                                                     0x01, 0xC5, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x12, 0x08,
                                                     0x00,
                                                     0x04,  // MAV_STATE_ACTIVE 4
                                                     0x03,
                                                     0x0E, 0x6A};  // CRC 0x6A0E
  EXPECT_EQ(second, expected_second);
  // and the reference CRC agrees with the hand-written checksum bytes
  std::uint16_t crc = reference_crc(&expected_first[1], 18);
  const std::uint8_t extra = 50;
  EXPECT_EQ(reference_crc(&extra, 1, crc), 0x681B);
}

TEST(MavlinkFraming, TrailingZerosAreTrimmedButOneByteStays) {
  Framer framer(1, 197);
  FrameBuffer frame{};
  // An all-zero payload keeps one byte.
  VisionPositionDelta zero;
  std::size_t n = framer.encode(zero, frame);
  EXPECT_EQ(frame[1], 1);
  EXPECT_EQ(n, 10u + 1 + 2);
  EXPECT_EQ(frame[10], 0);
  // A zero confidence (the last field) drops its 4 bytes; a zero time_usec (the first) does not.
  VisionPositionDelta d;
  d.time_delta_usec = 33333;
  d.angle_delta = {0.01f, -0.02f, 0.03f};
  d.position_delta = {0.1f, 0.2f, -0.3f};
  d.confidence = 0;
  n = framer.encode(d, frame);
  EXPECT_EQ(frame[1], 40);
  EXPECT_EQ(n, 10u + 40 + 2);
  Decoded dec = decode(frame, n, VisionPositionDelta::kCrcExtra, VisionPositionDelta::kPayloadBytes);
  EXPECT_EQ(read_le(dec.payload.data() + 8, 8), 33333u);
  EXPECT_EQ(read_f32(dec.payload, 40), 0.0f);
  // ODOMETRY with quality 0 (unknown) loses its last byte only.
  Odometry o;
  o.quality = 0;
  n = framer.encode(o, frame);
  EXPECT_EQ(frame[1], 232);
  // and with quality -1 keeps all 233 (0xFF is not zero).
  o.quality = -1;
  n = framer.encode(o, frame);
  EXPECT_EQ(frame[1], 233);
  EXPECT_EQ(frame[10 + 232], 0xFF);
  // trimmed_length alone
  const std::array<std::uint8_t, 5> p{7, 0, 3, 0, 0};
  EXPECT_EQ(trimmed_length(p), 3u);
  const std::array<std::uint8_t, 3> zeros{0, 0, 0};
  EXPECT_EQ(trimmed_length(zeros), 1u);
}

TEST(MavlinkFraming, SequenceWrapsAfter255PerFramer) {
  Framer a(1, 197), b(1, 197);
  FrameBuffer frame{};
  for (int i = 0; i < 300; ++i) {
    ASSERT_EQ(a.next_sequence(), static_cast<std::uint8_t>(i));
    (void)a.encode(Heartbeat{}, frame);
    ASSERT_EQ(frame[4], static_cast<std::uint8_t>(i)) << "frame " << i;
  }
  // Each framer counts its own link.
  (void)b.encode(Heartbeat{}, frame);
  EXPECT_EQ(frame[4], 0);
}

// A frame sent ahead of queued ones is numbered again as it leaves: the same bytes as a framer
// would have written at that sequence number, checksum included, for every message we send.
TEST(MavlinkFraming, RestampedFrameEqualsTheFrameEncodedAtThatSequence) {
  const auto check = [](const auto& message) {
    Framer early(1, 197), late(1, 197);
    FrameBuffer a{}, b{};
    const std::size_t n = early.encode(message, a);
    for (int i = 0; i < 77; ++i) (void)late.encode(Heartbeat{}, b);
    ASSERT_EQ(late.encode(message, b), n);
    ASSERT_TRUE(restamp_sequence(std::span<std::uint8_t>(a.data(), n), 77));
    EXPECT_TRUE(std::equal(a.begin(), a.begin() + static_cast<std::ptrdiff_t>(n), b.begin()));
  };
  check(Heartbeat{});
  Timesync t;
  t.tc1 = 123456789;
  check(t);
  Odometry o;
  o.x = 1.5f;
  check(o);
  check(VisionPositionDelta{});
  SetGpsGlobalOrigin g;
  g.latitude_deg_e7 = 473977420;
  check(g);
  check(SetHomePosition{});
  std::array<std::uint8_t, 12> not_ours{kMagicV2, 0, 0, 0, 0, 1, 1, 30, 0, 0, 0, 0};  // ATTITUDE
  EXPECT_FALSE(restamp_sequence(not_ours, 5));
  EXPECT_EQ(not_ours[4], 0);
}

TEST(MavlinkFraming, MessageIdIs24BitLittleEndian) {
  Framer framer(42, 197);
  FrameBuffer frame{};
  (void)framer.encode(Odometry{}, frame);
  EXPECT_EQ(frame[5], 42);
  EXPECT_EQ(frame[7], 0x4B);  // 331 = 0x00014B
  EXPECT_EQ(frame[8], 0x01);
  EXPECT_EQ(frame[9], 0x00);
  (void)framer.encode(VisionPositionDelta{}, frame);
  EXPECT_EQ(frame[7], 0x03);  // 11011 = 0x002B03
  EXPECT_EQ(frame[8], 0x2B);
  EXPECT_EQ(frame[9], 0x00);
}

TEST(MavlinkPayload, OdometryFieldsAtTheirWireOffsetsLittleEndian) {
  // GIVEN an ODOMETRY whose every field holds a distinct value
  Odometry o;
  o.time_usec = 0x0102030405060708ULL;
  o.frame_id = kMavFrameLocalFrd;
  o.child_frame_id = kMavFrameBodyFrd;
  o.x = 1.0f;
  o.y = -2.5f;
  o.z = 3.25f;
  o.q = {0.5f, -0.5f, 0.25f, -0.125f};
  o.vx = 4.f, o.vy = 5.f, o.vz = 6.f;
  o.rollspeed = 7.f, o.pitchspeed = 8.f, o.yawspeed = 9.f;
  for (int i = 0; i < 21; ++i) {
    o.pose_covariance[static_cast<std::size_t>(i)] = 100.f + static_cast<float>(i);
    o.velocity_covariance[static_cast<std::size_t>(i)] = 200.f + static_cast<float>(i);
  }
  o.reset_counter = 7;
  o.estimator_type = kMavEstimatorTypeVision;
  o.quality = -1;
  // WHEN framed and decoded by an independent receiver
  Framer framer(1, 197);
  FrameBuffer frame{};
  const std::size_t n = framer.encode(o, frame);
  const Decoded d = decode(frame, n, 91, 233);
  EXPECT_EQ(d.msgid, 331u);
  const auto& p = d.payload;
  // THEN each field sits where the wire order of common.xml puts it (offsets of the generated
  // mavlink_msg_odometry.h), least significant byte first
  EXPECT_EQ(p[0], 0x08);
  EXPECT_EQ(p[7], 0x01);
  EXPECT_EQ(read_le(&p[0], 8), 0x0102030405060708ULL);
  EXPECT_EQ(p[8], 0x00);  // 1.0f = 0x3F800000
  EXPECT_EQ(p[9], 0x00);
  EXPECT_EQ(p[10], 0x80);
  EXPECT_EQ(p[11], 0x3F);
  EXPECT_EQ(read_f32(p, 12), -2.5f);
  EXPECT_EQ(read_f32(p, 16), 3.25f);
  for (std::size_t i = 0; i < 4; ++i) EXPECT_EQ(read_f32(p, 20 + 4 * i), o.q[i]);
  EXPECT_EQ(read_f32(p, 36), 4.f);
  EXPECT_EQ(read_f32(p, 40), 5.f);
  EXPECT_EQ(read_f32(p, 44), 6.f);
  EXPECT_EQ(read_f32(p, 48), 7.f);
  EXPECT_EQ(read_f32(p, 52), 8.f);
  EXPECT_EQ(read_f32(p, 56), 9.f);
  for (std::size_t i = 0; i < 21; ++i) {
    EXPECT_EQ(read_f32(p, 60 + 4 * i), 100.f + static_cast<float>(i));
    EXPECT_EQ(read_f32(p, 144 + 4 * i), 200.f + static_cast<float>(i));
  }
  EXPECT_EQ(p[228], 20);  // frame_id MAV_FRAME_LOCAL_FRD
  EXPECT_EQ(p[229], 12);  // child_frame_id MAV_FRAME_BODY_FRD
  EXPECT_EQ(p[230], 7);   // reset_counter
  EXPECT_EQ(p[231], 2);   // estimator_type MAV_ESTIMATOR_TYPE_VISION
  EXPECT_EQ(static_cast<std::int8_t>(p[232]), -1);  // quality
}

TEST(MavlinkPayload, NanCovarianceMeansUnknownOnTheWire) {
  Odometry o;  // defaults: velocities and both covariances unknown
  std::array<std::uint8_t, Odometry::kPayloadBytes> p{};
  pack_payload(o, p);
  const std::vector<std::uint8_t> v(p.begin(), p.end());
  EXPECT_TRUE(std::isnan(read_f32(v, 60)));
  EXPECT_TRUE(std::isnan(read_f32(v, 144)));
  EXPECT_TRUE(std::isnan(read_f32(v, 36)));
}

TEST(MavlinkPayload, VisionPositionDeltaFieldsAtTheirWireOffsetsLittleEndian) {
  VisionPositionDelta m;
  m.time_usec = 1'700'000'000'123'456ULL;
  m.time_delta_usec = 33'367;
  m.angle_delta = {0.001f, -0.002f, 0.003f};
  m.position_delta = {0.04f, -0.05f, 0.06f};
  m.confidence = 87.5f;
  Framer framer(1, 197);
  FrameBuffer frame{};
  const std::size_t n = framer.encode(m, frame);
  const Decoded d = decode(frame, n, 106, 44);
  EXPECT_EQ(d.msgid, 11011u);
  EXPECT_EQ(n, 10u + 44 + 2);
  const auto& p = d.payload;
  EXPECT_EQ(read_le(&p[0], 8), m.time_usec);
  EXPECT_EQ(read_le(&p[8], 8), m.time_delta_usec);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(read_f32(p, 16 + 4 * i), m.angle_delta[i]);
    EXPECT_EQ(read_f32(p, 28 + 4 * i), m.position_delta[i]);
  }
  EXPECT_EQ(read_f32(p, 40), 87.5f);
  EXPECT_EQ(p[40], 0x00);  // 87.5f = 0x42AF0000
  EXPECT_EQ(p[41], 0x00);
  EXPECT_EQ(p[42], 0xAF);
  EXPECT_EQ(p[43], 0x42);
}

TEST(MavlinkPayload, HeartbeatFieldsAtTheirWireOffsets) {
  Heartbeat h;
  h.custom_mode = 0x0A0B0C0D;
  h.type = 1, h.autopilot = 2, h.base_mode = 0x51, h.system_status = 5;
  std::array<std::uint8_t, Heartbeat::kPayloadBytes> p{};
  pack_payload(h, p);
  const std::array<std::uint8_t, 9> expected{0x0D, 0x0C, 0x0B, 0x0A, 1, 2, 0x51, 5, 3};
  EXPECT_EQ(p, expected);
}

}  // namespace
}  // namespace rgbdo::mavlink
