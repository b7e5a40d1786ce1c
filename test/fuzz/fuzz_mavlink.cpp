// Any bytes from the flight computer, as a serial line delivers them (split anywhere) and as
// UDP datagrams (the parser reset between them): checked frames go where the link sends
// them, the autopilot watch and, for TIMESYNC, the clock estimator. Every byte must end up
// counted (mavlink_parser.hpp) and nothing may read outside a frame.
#include <cstdint>
#include <cstdlib>
#include <span>

#include "fuzz_input.hpp"
#include "rgbd_odometry/link/autopilot_watch.hpp"
#include "rgbd_odometry/link/mavlink.hpp"
#include "rgbd_odometry/link/mavlink_parser.hpp"
#include "rgbd_odometry/link/timesync.hpp"

namespace {

void consume(rgbdo::mavlink::FrameParser& parser, std::span<const std::uint8_t> bytes, rgbdo::AutopilotWatch& watch,
             rgbdo::TimesyncEstimator& timesync, std::int64_t& now_ns) {
  // As FlightLink::on_frame reads them.
  parser.feed(bytes, [&](const rgbdo::mavlink::ReceivedFrame& frame) {
    now_ns += 1'000'000;
    const rgbdo::AutopilotIdentity before = watch.state(now_ns).identity;
    if (!watch.accept(frame, now_ns)) return;
    if (watch.state(now_ns).identity != before) timesync.reset();
    if (frame.msgid != rgbdo::mavlink::Timesync::kId) return;
    const rgbdo::mavlink::Timesync m = rgbdo::mavlink::unpack_timesync(frame.payload);
    if (m.tc1 != 0) (void)timesync.add_answer(m.tc1, m.ts1, now_ns);
    (void)timesync.estimate();
    (void)timesync.to_autopilot_ns(now_ns);
  });
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace rgbdo;
  const std::span<const std::uint8_t> bytes(data, size);
  std::int64_t now_ns = 1'000'000'000;
  {
    mavlink::FrameParser parser;
    AutopilotWatch watch(0, 1, 197, 3'000'000'000);
    TimesyncEstimator timesync(50'000'000);
    timesync.note_request(now_ns);
    // A serial line: the bytes in pieces of the sizes the first byte chooses.
    const std::size_t piece = size > 0 ? 1 + data[0] % 64 : 1;
    for (std::size_t at = 0; at < size; at += piece) consume(parser, bytes.subspan(at, std::min(piece, size - at)), watch, timesync, now_ns);
    const mavlink::ParserCounts& c = parser.counts();
    if (c.frames_ok + c.crc_errors + c.unknown_ids + c.unsupported_flags > size) std::abort();  // a frame from nothing
  }
  {
    mavlink::FrameParser parser;
    AutopilotWatch watch(1, 1, 197, 3'000'000'000);
    TimesyncEstimator timesync(50'000'000);
    // Datagrams of up to 280 bytes, the parser reset between them as the UDP link does.
    for (std::size_t at = 0; at < size; at += 280) {
      parser.reset();
      consume(parser, bytes.subspan(at, std::min<std::size_t>(280, size - at)), watch, timesync, now_ns);
    }
  }
  return 0;
}
