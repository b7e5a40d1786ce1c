#pragma once
// Received MAVLink: splits a byte stream (a serial line, the datagrams of a UDP socket) into
// checked frames. MAVLink 2 (0xFD) and MAVLink 1 (0xFE) framing; the checksum with CRC_EXTRA
// is verified for the messages this program understands (HEARTBEAT, TIMESYNC, ATTITUDE,
// COMMAND_ACK: mavlink.hpp). Only those are delivered.
//
// Resynchronisation: no length field is trusted before the frame's checksum holds. A start
// byte that cannot begin a frame we can check (an id we have no CRC_EXTRA for, a length its
// message cannot have, incompat flags we do not know) is passed over on its header alone, and
// a frame that fails its checksum is passed over too: either way the search for the next start
// byte restarts at the byte after it. A false start byte in noise therefore never swallows the
// good frame that follows it (skipped by a random length field, it used to), and a good frame
// that began inside a bad one's bytes (a truncated frame followed by a whole one) is found. The
// price: the bytes of a genuine frame of another message are scanned for start bytes too, and
// counted as passed over, not skipped whole.
//
// Bounded: the bytes of one unfinished frame at most are kept (a fixed buffer, nothing is
// allocated, ever), any byte sequence at any rate only advances counters. Signed MAVLink 2
// frames (incompat flag 0x01) carry 13 signature bytes after the checksum; they are skipped
// with the frame. The signature is not verified (this program has no key): a signed frame
// whose checksum holds is delivered, flagged is_signed.
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "rgbd_odometry/link/mavlink.hpp"

namespace rgbdo::mavlink {

inline constexpr std::size_t kHeaderBytesV1 = 6;  // magic len seq sysid compid msgid
inline constexpr std::array<std::uint8_t, kMaxPayloadBytes> kNoPayload{};  // what a frame's span holds before use

// One checked frame. Valid until the next call into the parser that produced it.
struct ReceivedFrame {
  std::uint8_t version = 2;  // 1 or 2
  std::uint8_t seq = 0, sysid = 0, compid = 0;
  std::uint32_t msgid = 0;
  std::uint8_t payload_length = 0;  // as sent (MAVLink 2 trims trailing zero bytes)
  bool is_signed = false;
  // The payload zero-extended to the largest size: the trimmed bytes (and extension fields a
  // MAVLink 1 sender does not have) read as zero, as the protocol says.
  std::span<const std::uint8_t, kMaxPayloadBytes> payload{kNoPayload};
};

// Counters since the parser was made. Every byte fed ends up in a delivered frame,
// bytes_discarded, or (for now) the unfinished frame.
struct ParserCounts {
  std::uint64_t frames_ok = 0;         // checksum verified, delivered
  std::uint64_t crc_errors = 0;        // known id, wrong checksum or a length its message cannot have
  std::uint64_t unknown_ids = 0;       // start bytes passed over: no CRC_EXTRA known for the id
  std::uint64_t unsupported_flags = 0; // MAVLink 2 incompat flags other than "signed"
  std::uint64_t signed_frames = 0;     // of frames_ok
  std::uint64_t bytes_discarded = 0;   // not in a delivered frame: noise, passed-over frames, reset()
};

// What the parser checks a message by: its CRC_EXTRA and its longest payload (MAVLink 2
// trims trailing zeros, so a payload may be shorter, never longer).
struct CheckedMessage {
  std::uint8_t crc_extra = 0;
  std::size_t max_payload_bytes = 0;
};
[[nodiscard]] std::optional<CheckedMessage> checked_message(std::uint32_t msgid);
// CRC_EXTRA of the message ids this program reads, or nothing.
[[nodiscard]] std::optional<std::uint8_t> crc_extra_of(std::uint32_t msgid);

class FrameParser {
 public:
  // Calls on_frame(const ReceivedFrame&) for each checked frame of `bytes`, in stream order.
  // The bytes of an unfinished frame at the end are kept for the next call.
  template <typename OnFrame>
  void feed(std::span<const std::uint8_t> bytes, OnFrame&& on_frame) {
    while (!bytes.empty()) {
      bytes = bytes.subspan(append(bytes));
      ReceivedFrame frame;
      while (next_frame(frame)) on_frame(static_cast<const ReceivedFrame&>(frame));
      compact();
    }
  }

  // The end of a UDP datagram, which holds whole frames: a frame is never continued by the
  // next datagram. What looked like the start of an unfinished frame was a false start: its
  // start byte is passed over and the rest searched again, so a good frame inside it is still
  // delivered; what is left after that is counted as discarded.
  template <typename OnFrame>
  void end_datagram(OnFrame&& on_frame) {
    while (scan_ < size_) {
      ++counts_.bytes_discarded;
      ++scan_;
      ReceivedFrame frame;
      while (next_frame(frame)) on_frame(static_cast<const ReceivedFrame&>(frame));
    }
    size_ = scan_ = 0;
  }

  // Forget an unfinished frame (its bytes are counted as discarded).
  void reset();

  const ParserCounts& counts() const { return counts_; }

 private:
  // Room for one unfinished frame plus at least one whole frame of new bytes.
  static constexpr std::size_t kBufferBytes = 2 * kMaxFrameBytes;

  std::size_t append(std::span<const std::uint8_t> bytes);  // returns how many were taken
  bool next_frame(ReceivedFrame& out);  // from scan_, advancing it; false: needs more bytes
  void compact();                       // drops the scanned bytes

  std::array<std::uint8_t, kBufferBytes> buffer_{};
  std::size_t size_ = 0;  // bytes in buffer_
  std::size_t scan_ = 0;  // bytes of buffer_ already consumed
  std::array<std::uint8_t, kMaxPayloadBytes> payload_{};
  ParserCounts counts_;
};

}  // namespace rgbdo::mavlink
