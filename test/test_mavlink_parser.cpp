// Received MAVLink (src/link/mavlink_parser.cpp): frames built independently here
// (mavlink_reference.hpp: bit-serial CRC, CRC_EXTRA derived from the XML field lists) are
// split out of byte streams with garbage between them, truncated, corrupted, signed, in
// MAVLink 1 and 2, fed whole or a byte at a time; a flood of random bytes only moves counters.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

#include "rgbd_odometry/link/mavlink_parser.hpp"
#include "mavlink_reference.hpp"

namespace rgbdo::mavlink {
namespace {

using namespace mavlink_reference;
using Bytes = std::vector<std::uint8_t>;

// common.xml TIMESYNC, in XML order (target_* are extensions, added in 2022).
const std::vector<XmlField> kTimesyncXml = {{"int64_t", "tc1"},
                                            {"int64_t", "ts1"},
                                            {"uint8_t", "target_system", 0, true},
                                            {"uint8_t", "target_component", 0, true}};
// common.xml COMMAND_ACK (progress .. target_component are extensions).
const std::vector<XmlField> kCommandAckXml = {{"uint16_t", "command"},
                                              {"uint8_t", "result"},
                                              {"uint8_t", "progress", 0, true},
                                              {"int32_t", "result_param2", 0, true},
                                              {"uint8_t", "target_system", 0, true},
                                              {"uint8_t", "target_component", 0, true}};
const std::vector<XmlField> kHeartbeatXml = {{"uint8_t", "type"},          {"uint8_t", "autopilot"},
                                             {"uint8_t", "base_mode"},     {"uint32_t", "custom_mode"},
                                             {"uint8_t", "system_status"}, {"uint8_t", "mavlink_version"}};

Bytes heartbeat_payload(std::uint8_t type, std::uint8_t autopilot, std::uint32_t custom_mode) {
  // Wire order: custom_mode (4 bytes) first, then the uint8 fields in XML order.
  return {static_cast<std::uint8_t>(custom_mode), static_cast<std::uint8_t>(custom_mode >> 8),
          static_cast<std::uint8_t>(custom_mode >> 16), static_cast<std::uint8_t>(custom_mode >> 24),
          type, autopilot, 0x51 /*base_mode*/, 4 /*system_status*/, 3 /*mavlink_version*/};
}

// Trimmed as MAVLink 2 senders do: trailing zeros cut, at least one byte kept.
Bytes trim(Bytes p) {
  while (p.size() > 1 && p.back() == 0) p.pop_back();
  return p;
}

Bytes timesync_payload(std::int64_t tc1, std::int64_t ts1, std::uint8_t target_system, std::uint8_t target_component,
                       bool extensions = true) {
  Bytes p(extensions ? 18 : 16);
  for (int i = 0; i < 8; ++i) {
    p[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(static_cast<std::uint64_t>(tc1) >> (8 * i));
    p[static_cast<std::size_t>(8 + i)] = static_cast<std::uint8_t>(static_cast<std::uint64_t>(ts1) >> (8 * i));
  }
  if (extensions) {
    p[16] = target_system;
    p[17] = target_component;
  }
  return p;
}

Bytes heartbeat_frame(std::uint8_t seq, int version = 2) {
  return build_frame(version, 0, derive_crc_extra("HEARTBEAT", kHeartbeatXml), heartbeat_payload(2, 12, 0x10000 + seq),
                     seq, 1, 1);
}
Bytes timesync_frame(std::int64_t tc1, std::int64_t ts1, std::uint8_t seq) {
  return build_frame(2, 111, derive_crc_extra("TIMESYNC", kTimesyncXml), trim(timesync_payload(tc1, ts1, 0, 0)), seq,
                     1, 1);
}

struct Seen {
  std::uint8_t version, seq, sysid, compid;
  std::uint32_t msgid;
  bool is_signed;
  Bytes payload;  // the full zero-extended payload, first 32 bytes
};

std::vector<Seen> parse(FrameParser& parser, const Bytes& stream, std::size_t chunk = 0) {
  std::vector<Seen> seen;
  auto on_frame = [&](const ReceivedFrame& f) {
    seen.push_back({f.version, f.seq, f.sysid, f.compid, f.msgid, f.is_signed, Bytes(f.payload.begin(), f.payload.begin() + 32)});
  };
  if (chunk == 0) {
    parser.feed(stream, on_frame);
  } else {
    for (std::size_t i = 0; i < stream.size(); i += chunk)
      parser.feed(std::span<const std::uint8_t>(stream).subspan(i, std::min(chunk, stream.size() - i)), on_frame);
  }
  return seen;
}

Bytes concat(std::initializer_list<Bytes> parts) {
  Bytes all;
  for (const auto& p : parts) all.insert(all.end(), p.begin(), p.end());
  return all;
}

TEST(MavlinkParserDefinitions, CrcExtraOfTheMessagesReadIsDerivedFromTheirFieldLists) {
  EXPECT_EQ(derive_crc_extra("TIMESYNC", kTimesyncXml), 34);
  EXPECT_EQ(derive_crc_extra("HEARTBEAT", kHeartbeatXml), 50);
  EXPECT_EQ(crc_extra_of(Timesync::kId), derive_crc_extra("TIMESYNC", kTimesyncXml));
  EXPECT_EQ(crc_extra_of(Heartbeat::kId), derive_crc_extra("HEARTBEAT", kHeartbeatXml));
  EXPECT_FALSE(crc_extra_of(331).has_value()) << "ODOMETRY is sent, never read";
  EXPECT_EQ(crc_extra_of(CommandAck::kId), derive_crc_extra("COMMAND_ACK", kCommandAckXml));
  EXPECT_EQ(CommandAck::kPayloadBytes, wire_length(kCommandAckXml, true));
  EXPECT_EQ(CommandAck::kResultOffset, wire_offset(kCommandAckXml, "result"));
  EXPECT_EQ(CommandAck::kTargetComponentOffset, wire_offset(kCommandAckXml, "target_component"));
  EXPECT_EQ(Timesync::kPayloadBytes, wire_length(kTimesyncXml, true));
  EXPECT_EQ(Timesync::kBasePayloadBytes, wire_length(kTimesyncXml, false));
  EXPECT_EQ(Timesync::kTs1Offset, wire_offset(kTimesyncXml, "ts1"));
  EXPECT_EQ(Timesync::kTargetComponentOffset, wire_offset(kTimesyncXml, "target_component"));
}

TEST(MavlinkParserDefinitions, TimesyncEncodesToTheGoldenFrame) {
  Framer framer(1, 197);
  FrameBuffer out{};
  Timesync m;
  m.tc1 = 1'234'567'890'123'456'789;
  m.ts1 = -42;  // int64: two's complement on the wire
  m.target_system = 1;
  m.target_component = 1;
  const std::size_t n = framer.encode(m, out);
  const Bytes golden = build_frame(2, 111, 34, timesync_payload(m.tc1, m.ts1, 1, 1), 0, 1, 197);
  ASSERT_EQ(n, golden.size());
  EXPECT_TRUE(std::equal(golden.begin(), golden.end(), out.begin()));
  // And it reads back.
  FrameParser parser;
  const auto seen = parse(parser, Bytes(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(n)));
  ASSERT_EQ(seen.size(), 1u);
  std::array<std::uint8_t, kMaxPayloadBytes> full{};
  std::copy(seen[0].payload.begin(), seen[0].payload.end(), full.begin());
  const Timesync back = unpack_timesync(full);
  EXPECT_EQ(back.tc1, m.tc1);
  EXPECT_EQ(back.ts1, m.ts1);
  EXPECT_EQ(back.target_system, 1);
  EXPECT_EQ(back.target_component, 1);
}

TEST(MavlinkParser, HeartbeatV2FieldsAsSent) {
  FrameParser parser;
  const auto seen = parse(parser, heartbeat_frame(7));
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].version, 2);
  EXPECT_EQ(seen[0].seq, 7);
  EXPECT_EQ(seen[0].sysid, 1);
  EXPECT_EQ(seen[0].compid, 1);
  EXPECT_EQ(seen[0].msgid, 0u);
  std::array<std::uint8_t, kMaxPayloadBytes> full{};
  std::copy(seen[0].payload.begin(), seen[0].payload.end(), full.begin());
  const Heartbeat hb = unpack_heartbeat(full);
  EXPECT_EQ(hb.type, 2);
  EXPECT_EQ(hb.autopilot, kMavAutopilotPx4);
  EXPECT_EQ(hb.custom_mode, 0x10007u);
  EXPECT_EQ(hb.mavlink_version, 3);
  EXPECT_EQ(parser.counts().frames_ok, 1u);
  EXPECT_EQ(parser.counts().bytes_discarded, 0u);
}

TEST(MavlinkParser, MavlinkOneFramesAreReadToo) {
  FrameParser parser;
  // A v1 TIMESYNC has no extension fields: they read as zero.
  const Bytes v1 = build_frame(1, 111, 34, timesync_payload(0, 987654321, 9, 9, false), 3, 1, 1);
  const auto seen = parse(parser, concat({v1, heartbeat_frame(4, 1)}));
  ASSERT_EQ(seen.size(), 2u);
  EXPECT_EQ(seen[0].version, 1);
  EXPECT_EQ(seen[0].msgid, 111u);
  EXPECT_EQ(seen[0].payload[8], 0xB1);  // 987654321 = 0x3ADE68B1
  EXPECT_EQ(seen[0].payload[16], 0) << "absent extension reads as zero";
  EXPECT_EQ(seen[1].version, 1);
  EXPECT_EQ(seen[1].seq, 4);
}

TEST(MavlinkParser, TrimmedPayloadIsZeroExtended) {
  FrameParser parser;
  const Bytes f = timesync_frame(0, 0x0102, 1);  // request: tc1 0, small ts1: 10 of 18 bytes trimmed
  ASSERT_EQ(f[1], 10);
  // Bytes the previous, longer frame left in the parser's buffer must not show through.
  const Bytes before = build_frame(2, 111, 34, timesync_payload(-1, -1, 0xAA, 0xBB), 0, 1, 1);
  const auto seen = parse(parser, concat({before, f}));
  ASSERT_EQ(seen.size(), 2u);
  EXPECT_EQ(seen[1].payload[8], 0x02);
  EXPECT_EQ(seen[1].payload[9], 0x01);
  for (std::size_t i = 10; i < 32; ++i) EXPECT_EQ(seen[1].payload[i], 0) << "byte " << i;
}

TEST(MavlinkParser, GarbageBetweenFramesIsDiscardedAndCounted) {
  const Bytes garbage = {0x00, 0x11, 0x22, 0x33, 0x44, 0x55, 0xFC, 0xFF, 0x0A, 0x0D};  // no start byte
  const Bytes stream = concat({garbage, heartbeat_frame(1), garbage, garbage, timesync_frame(0, 5, 2), garbage});
  for (std::size_t chunk : {0u, 1u, 2u, 7u, 64u}) {
    FrameParser parser;
    const auto seen = parse(parser, stream, chunk);
    ASSERT_EQ(seen.size(), 2u) << "chunk " << chunk;
    EXPECT_EQ(seen[0].seq, 1);
    EXPECT_EQ(seen[1].seq, 2);
    EXPECT_EQ(parser.counts().bytes_discarded, 4 * garbage.size()) << "chunk " << chunk;
    EXPECT_EQ(parser.counts().crc_errors, 0u);
  }
}

TEST(MavlinkParser, WrongChecksumIsRejectedAndTheNextFrameKept) {
  Bytes bad = heartbeat_frame(1);
  bad[12] ^= 0x01;  // a payload bit
  Bytes bad_crc = timesync_frame(0, 77, 2);
  bad_crc.back() ^= 0x80;
  FrameParser parser;
  const auto seen = parse(parser, concat({bad, bad_crc, heartbeat_frame(3)}));
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].seq, 3);
  EXPECT_EQ(parser.counts().crc_errors, 2u);
  EXPECT_EQ(parser.counts().frames_ok, 1u);
}

TEST(MavlinkParser, AGoodFrameThatBeganInsideATruncatedOneIsFound) {
  // GIVEN a heartbeat cut after 12 of its 21 bytes, directly followed by a whole TIMESYNC: the
  // cut frame's length field claims the TIMESYNC's first bytes as its own
  const Bytes whole = heartbeat_frame(1);
  const Bytes cut(whole.begin(), whole.begin() + 12);
  const Bytes next = timesync_frame(0, 123456789, 2);
  for (std::size_t chunk : {0u, 1u, 5u}) {
    FrameParser parser;
    // WHEN both are parsed
    const auto seen = parse(parser, concat({cut, next, heartbeat_frame(3)}), chunk);
    // THEN the truncated one fails its checksum and the search resumes inside it
    ASSERT_EQ(seen.size(), 2u) << "chunk " << chunk;
    EXPECT_EQ(seen[0].msgid, 111u);
    EXPECT_EQ(seen[0].seq, 2);
    EXPECT_EQ(seen[1].seq, 3);
    EXPECT_EQ(parser.counts().crc_errors, 1u);
    EXPECT_EQ(parser.counts().bytes_discarded, cut.size());
  }
}

TEST(MavlinkParser, FramesOfOtherMessagesArePassedOverByteByByte) {
  // A SYS_STATUS (#1, 31 bytes) and a MAVLink 1 message #200: no CRC_EXTRA known here, so
  // their lengths cannot be checked and are not trusted. Their payloads hold start bytes,
  // none of which may be taken for a frame; every one of their bytes is counted as passed over.
  Bytes payload(31, 0xFD);
  const Bytes sys_status = build_frame(2, 1, 124, payload, 1, 1, 1);
  const Bytes odometry_v1 = build_frame(1, 200, 0, Bytes(20, 0xFE), 2, 1, 1);
  for (std::size_t chunk : {0u, 1u, 7u}) {
    FrameParser parser;
    const auto seen = parse(parser, concat({sys_status, odometry_v1, heartbeat_frame(3)}), chunk);
    ASSERT_EQ(seen.size(), 1u) << "chunk " << chunk;
    EXPECT_EQ(seen[0].seq, 3);
    EXPECT_GE(parser.counts().unknown_ids, 2u);
    EXPECT_EQ(parser.counts().bytes_discarded, sys_status.size() + odometry_v1.size());
  }
}

TEST(MavlinkParser, AFalseStartInNoiseDoesNotSwallowTheFrameAfterIt) {
  // Noise that begins like a frame: a start byte, a long length, an id nobody reads, then a
  // good TIMESYNC well inside the length the noise announced. Skipped by that length, the
  // TIMESYNC was lost (a PX4 on a noisy line saw 13 % of its requests unanswered).
  const Bytes false_start = {0xFD, 200, 0, 0, 9, 1, 1, 0x4D, 0x01, 0x00, 0x12, 0x34};
  const Bytes request = timesync_frame(0, 123456789, 7);
  for (std::size_t chunk : {0u, 1u, 5u}) {
    FrameParser parser;
    const auto seen = parse(parser, concat({false_start, request}), chunk);
    ASSERT_EQ(seen.size(), 1u) << "chunk " << chunk;
    EXPECT_EQ(seen[0].msgid, Timesync::kId);
    EXPECT_EQ(seen[0].seq, 7);
    EXPECT_EQ(parser.counts().unknown_ids, 1u);
    EXPECT_EQ(parser.counts().bytes_discarded, false_start.size());
  }
  // A known id with a length its message cannot have (HEARTBEAT has 9 bytes) is refused on
  // its header: the frame after it is delivered without waiting for 250 more bytes.
  const Bytes impossible = {0xFD, 250, 0, 0, 9, 1, 1, 0, 0, 0};
  FrameParser parser;
  const auto seen = parse(parser, concat({impossible, heartbeat_frame(4)}));
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].seq, 4);
  EXPECT_EQ(parser.counts().crc_errors, 1u);
}

TEST(MavlinkParser, EveryFrameSurvivesRandomNoiseOfEveryByteBetweenThem) {
  // Noise of the whole byte range, start bytes included, between 400 frames: a false start
  // may announce any length and any id, and each frame must still come out.
  std::mt19937 rng(17);
  Bytes stream;
  for (int i = 0; i < 400; ++i) {
    for (int g = static_cast<int>(rng() % 40); g > 0; --g) stream.push_back(static_cast<std::uint8_t>(rng()));
    if (rng() % 3 == 0) stream.push_back(rng() % 2 ? kMagicV2 : kMagicV1);  // a false start right before it
    const Bytes f = i % 4 == 0 ? heartbeat_frame(static_cast<std::uint8_t>(i))
                               : timesync_frame(0, 1000 + i, static_cast<std::uint8_t>(i));
    stream.insert(stream.end(), f.begin(), f.end());
  }
  for (std::size_t chunk : {0u, 1u, 13u, 280u}) {
    FrameParser parser;
    const auto seen = parse(parser, stream, chunk);
    ASSERT_EQ(seen.size(), 400u) << "chunk " << chunk;
    for (int i = 0; i < 400; ++i) ASSERT_EQ(seen[static_cast<std::size_t>(i)].seq, static_cast<std::uint8_t>(i));
  }
}

TEST(MavlinkParser, TheEndOfADatagramFindsAFrameInsideAFalseStart) {
  // A false start whose announced frame (an ATTITUDE's 28 bytes) runs past the datagram's end
  // holds a whole heartbeat: the end of the datagram passes over its start byte and finds it.
  const Bytes false_start = {0xFD, 28, 0, 0, 9, 1, 1, 30, 0, 0};
  const Bytes datagram = concat({false_start, heartbeat_frame(5)});
  FrameParser parser;
  std::vector<std::uint8_t> seqs;
  parser.feed(datagram, [&](const ReceivedFrame& f) { seqs.push_back(f.seq); });
  EXPECT_TRUE(seqs.empty()) << "a stream would wait for the rest of the ATTITUDE";
  parser.end_datagram([&](const ReceivedFrame& f) { seqs.push_back(f.seq); });
  ASSERT_EQ(seqs.size(), 1u);
  EXPECT_EQ(seqs[0], 5);
  EXPECT_EQ(parser.counts().bytes_discarded, false_start.size());
  EXPECT_EQ(parse(parser, heartbeat_frame(6)).size(), 1u) << "nothing of the datagram is left";
}

// ATTITUDE is read (the local frame is levelled with it): checked with its CRC_EXTRA 39.
TEST(MavlinkParser, AttitudeIsCheckedAndReadBack) {
  Bytes payload(28, 0);
  const float roll = 0.0312f, pitch = -0.0187f;
  std::memcpy(payload.data() + 4, &roll, 4);  // both targets are little-endian
  std::memcpy(payload.data() + 8, &pitch, 4);
  FrameParser parser;
  auto seen = parse(parser, concat({build_frame(2, 30, 39, payload, 5, 1, 1), build_frame(2, 30, 38, payload, 6, 1, 1)}));
  ASSERT_EQ(seen.size(), 1u) << "the one with the wrong CRC_EXTRA is refused";
  EXPECT_EQ(parser.counts().crc_errors, 1u);
  std::array<std::uint8_t, kMaxPayloadBytes> zero_extended{};
  std::copy(seen[0].payload.begin(), seen[0].payload.end(), zero_extended.begin());
  const Attitude a = unpack_attitude(zero_extended);
  EXPECT_EQ(a.roll, roll);
  EXPECT_EQ(a.pitch, pitch);
}

TEST(MavlinkParser, SignedFramesAreSkippedWithTheirSignature) {
  // The 13 signature bytes (link id, 6-byte timestamp, 6-byte signature) hold start bytes.
  const Bytes signature = {0x01, 0xFD, 0xFE, 0xFD, 0x00, 0x00, 0x00, 0xFD, 0xFE, 0xFD, 0x09, 0xFD, 0xFD};
  const Bytes signed_hb =
      build_frame(2, 0, 50, heartbeat_payload(2, 3, 0), 1, 1, 1, kIncompatFlagSigned, signature);
  const Bytes signed_unknown = build_frame(2, 1, 124, Bytes(31, 7), 2, 1, 1, kIncompatFlagSigned, signature);
  for (std::size_t chunk : {0u, 1u, 3u}) {
    FrameParser parser;
    const auto seen = parse(parser, concat({signed_hb, signed_unknown, heartbeat_frame(3)}), chunk);
    ASSERT_EQ(seen.size(), 2u) << "chunk " << chunk;
    EXPECT_TRUE(seen[0].is_signed);
    EXPECT_EQ(seen[0].payload[5], 3) << "ArduPilot";
    EXPECT_FALSE(seen[1].is_signed);
    EXPECT_EQ(seen[1].seq, 3);
    EXPECT_EQ(parser.counts().signed_frames, 1u);
    EXPECT_GE(parser.counts().unknown_ids, 1u);
    EXPECT_EQ(parser.counts().bytes_discarded, signed_unknown.size()) << "the checked signed frame is skipped whole";
  }
}

TEST(MavlinkParser, UnknownIncompatFlagsAreRejected) {
  const Bytes odd = build_frame(2, 0, 50, heartbeat_payload(2, 12, 0), 1, 1, 1, 0x02);
  FrameParser parser;
  const auto seen = parse(parser, concat({odd, heartbeat_frame(2)}));
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].seq, 2);
  EXPECT_EQ(parser.counts().unsupported_flags, 1u);
}

TEST(MavlinkParser, ResetForgetsAnUnfinishedFrame) {
  const Bytes whole = heartbeat_frame(1);
  FrameParser parser;
  EXPECT_TRUE(parse(parser, Bytes(whole.begin(), whole.begin() + 15)).empty());
  parser.reset();  // a new datagram
  EXPECT_TRUE(parse(parser, Bytes(whole.begin() + 15, whole.end())).empty());
  EXPECT_EQ(parser.counts().bytes_discarded, whole.size());
  EXPECT_EQ(parse(parser, heartbeat_frame(2)).size(), 1u);
}

TEST(MavlinkParser, EveryFrameOfALongStreamSurvivesEveryChunking) {
  Bytes stream;
  std::mt19937 rng(5);
  for (int i = 0; i < 300; ++i) {
    const Bytes f = i % 3 == 0 ? heartbeat_frame(static_cast<std::uint8_t>(i), 1 + i % 2)
                               : timesync_frame(i % 2 ? 0 : i * 1000003LL, i * 999983LL, static_cast<std::uint8_t>(i));
    stream.insert(stream.end(), f.begin(), f.end());
    for (int g = static_cast<int>(rng() % 5); g > 0; --g) stream.push_back(static_cast<std::uint8_t>(rng() % 0xFD));
  }
  for (std::size_t chunk : {0u, 1u, 13u, 279u, 280u, 281u, 4096u}) {
    FrameParser parser;
    const auto seen = parse(parser, stream, chunk);
    ASSERT_EQ(seen.size(), 300u) << "chunk " << chunk;
    for (int i = 0; i < 300; ++i) ASSERT_EQ(seen[static_cast<std::size_t>(i)].seq, static_cast<std::uint8_t>(i));
  }
}

TEST(MavlinkParser, AFloodOfRandomBytesOnlyMovesCounters) {
  // Random bytes, rich in start bytes (1 in 4), with good frames sprinkled in: nothing
  // crashes (the sanitizer builds run this too), every byte is accounted for, and a good
  // frame after the flood is found.
  std::mt19937 rng(11);
  FrameParser parser;
  Bytes chunk(4096);
  std::size_t fed = 0;
  for (int round = 0; round < 500; ++round) {
    for (auto& b : chunk) {
      const unsigned r = rng();
      b = (r & 3) == 0 ? static_cast<std::uint8_t>(0xFD + ((r >> 2) & 1)) : static_cast<std::uint8_t>(r >> 8);
    }
    if (round % 10 == 0) {
      const Bytes hb = heartbeat_frame(static_cast<std::uint8_t>(round));
      std::copy(hb.begin(), hb.end(), chunk.begin() + 1000);
    }
    parse(parser, chunk, 1 + rng() % 600);
    fed += chunk.size();
  }
  parser.reset();
  const auto seen = parse(parser, heartbeat_frame(99));
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].seq, 99);
  const ParserCounts& c = parser.counts();
  EXPECT_GT(c.crc_errors + c.unknown_ids + c.unsupported_flags, 0u);
  EXPECT_LE(c.bytes_discarded, fed);
}

}  // namespace
}  // namespace rgbdo::mavlink
