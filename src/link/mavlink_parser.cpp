#include "rgbd_odometry/link/mavlink_parser.hpp"

#include <algorithm>
#include <cstring>

namespace rgbdo::mavlink {

std::optional<CheckedMessage> checked_message(std::uint32_t msgid) {
  switch (msgid) {
    case Heartbeat::kId: return CheckedMessage{Heartbeat::kCrcExtra, Heartbeat::kPayloadBytes};
    case Timesync::kId: return CheckedMessage{Timesync::kCrcExtra, Timesync::kPayloadBytes};
    case Attitude::kId: return CheckedMessage{Attitude::kCrcExtra, Attitude::kPayloadBytes};
    case CommandAck::kId: return CheckedMessage{CommandAck::kCrcExtra, CommandAck::kPayloadBytes};
    default: return std::nullopt;
  }
}

std::optional<std::uint8_t> crc_extra_of(std::uint32_t msgid) {
  const auto m = checked_message(msgid);
  return m ? std::optional<std::uint8_t>(m->crc_extra) : std::nullopt;
}

std::size_t FrameParser::append(std::span<const std::uint8_t> bytes) {
  const std::size_t n = std::min(bytes.size(), buffer_.size() - size_);
  std::memcpy(buffer_.data() + size_, bytes.data(), n);
  size_ += n;
  return n;
}

void FrameParser::compact() {
  // What is left is at most one unfinished frame (next_frame stops only there), so at least
  // kBufferBytes - kMaxFrameBytes bytes are free after this.
  std::memmove(buffer_.data(), buffer_.data() + scan_, size_ - scan_);
  size_ -= scan_;
  scan_ = 0;
}

void FrameParser::reset() {
  counts_.bytes_discarded += size_ - scan_;
  size_ = scan_ = 0;
}

bool FrameParser::next_frame(ReceivedFrame& out) {
  for (;;) {
    // The next start byte; everything before it is noise.
    const std::uint8_t* begin = buffer_.data() + scan_;
    const std::uint8_t* end = buffer_.data() + size_;
    const std::uint8_t* start =
        std::find_if(begin, end, [](std::uint8_t b) { return b == kMagicV2 || b == kMagicV1; });
    counts_.bytes_discarded += static_cast<std::size_t>(start - begin);
    scan_ = static_cast<std::size_t>(start - buffer_.data());
    const std::size_t available = size_ - scan_;
    const bool v2 = available > 0 && *start == kMagicV2;
    const std::size_t header = v2 ? kHeaderBytes : kHeaderBytesV1;
    if (available < header) return false;

    const std::uint8_t length = start[1];
    std::uint8_t incompat = 0;
    if (v2) {
      incompat = start[2];
      out.seq = start[4];
      out.sysid = start[5];
      out.compid = start[6];
      out.msgid = static_cast<std::uint32_t>(start[7]) | static_cast<std::uint32_t>(start[8]) << 8 |
                  static_cast<std::uint32_t>(start[9]) << 16;
    } else {
      out.seq = start[2];
      out.sysid = start[3];
      out.compid = start[4];
      out.msgid = start[5];
    }
    // Decided on the header alone, without waiting for the rest: a start byte that cannot
    // begin a frame we can check (flags we do not know, an id we have no CRC_EXTRA for, a
    // length the message cannot have) is passed over, and the search goes on from the byte
    // after it. Its length field is not trusted: after a false start in noise it would
    // swallow the good frame that follows.
    const std::optional<CheckedMessage> message = checked_message(out.msgid);
    if ((incompat & ~kIncompatFlagSigned) != 0 || !message || length > message->max_payload_bytes) {
      if ((incompat & ~kIncompatFlagSigned) != 0)
        ++counts_.unsupported_flags;
      else if (!message)
        ++counts_.unknown_ids;
      else
        ++counts_.crc_errors;
      ++counts_.bytes_discarded;
      ++scan_;
      continue;
    }
    const bool is_signed = (incompat & kIncompatFlagSigned) != 0;
    const std::size_t frame_bytes = header + length + kChecksumBytes + (is_signed ? kSignatureBytes : 0);
    if (available < frame_bytes) return false;

    std::uint16_t crc = crc16_mcrf4xx(std::span<const std::uint8_t>(start + 1, header - 1 + length));
    crc = crc_accumulate(message->crc_extra, crc);
    const std::uint16_t received =
        static_cast<std::uint16_t>(start[header + length] | (start[header + length + 1] << 8));
    if (crc != received) {
      ++counts_.crc_errors;
      ++counts_.bytes_discarded;  // the start byte; the search goes on from the byte after it
      ++scan_;
      continue;
    }
    std::memcpy(payload_.data(), start + header, length);
    std::fill(payload_.begin() + length, payload_.end(), std::uint8_t{0});
    out.version = v2 ? 2 : 1;
    out.payload_length = length;
    out.is_signed = is_signed;
    out.payload = payload_;
    ++counts_.frames_ok;
    if (is_signed) ++counts_.signed_frames;
    scan_ += frame_bytes;
    return true;
  }
}

}  // namespace rgbdo::mavlink
