#pragma once
// The byte transports that carry encoded MAVLink 2 frames between the odometry program and
// the flight computer: UDP to a fixed peer or listening for one (src/link/transport_udp.cpp)
// and a serial port (src/link/transport_serial.cpp), chosen by a URI at start-up
// (src/link/transport.cpp). Frames go out from the output thread (send) and come in on the
// same socket or port on a receiver thread of their own (receive).
//
// The promise to the pipeline: send() never blocks and never throws, whatever the transport
// (or the receiver thread) is doing. A link that is down, a peer that is not listening, a full buffer or an unplugged
// USB adapter cost a counted drop and a problem text, never a stalled output thread, and the
// link recovers by itself when the far end comes back. Only construction throws (LinkError),
// and only for configurations that waiting cannot fix.
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <variant>

namespace rgbdo {

// A link URI or option that cannot work as written; the message names the input and the problem.
class LinkError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// MAVLink 2's largest frame: 10 header + 255 payload + 2 checksum + 13 signature bytes (the
// same as mavlink::kMaxFrameBytes; the transports need no MAVLink header, only this bound).
inline constexpr std::size_t kMaxLinkFrameBytes = 280;
static_assert(kMaxLinkFrameBytes == 10 + 255 + 2 + 13);

// What happened to one frame handed to send(). The odometry thread may ignore it (the counts
// in LinkStats say the same thing), which is why it is not [[nodiscard]].
enum class SendResult {
  Sent,                 // UDP: the kernel took the datagram
  Queued,               // serial: waiting for the writer thread
  QueuedDroppedOldest,  // serial: the queue was full; its oldest frame was discarded for this one
  DroppedBufferFull,    // UDP: the socket's send buffer is full (EAGAIN / ENOBUFS)
  DroppedLinkDown,      // UDP: no route yet, or the peer refused the previous datagram
  Rejected,             // empty or longer than kMaxLinkFrameBytes; nothing was sent
};

// What one receive() call brought.
struct ReceiveResult {
  std::size_t bytes = 0;  // 0: nothing arrived within the timeout (or the link is down)
  // UDP: the bytes are one whole datagram (frames never continue into the next one).
  // Serial: a piece of the byte stream.
  bool datagram = false;
};

// Counters since the link was opened. Every frame given to send() ends up in exactly one of
// sent, dropped_queue_full, dropped_link_down, rejected or (serial) pending.
struct LinkStats {
  std::uint64_t frames_sent = 0;  // whole frames handed to the kernel (serial: fully written)
  std::uint64_t bytes_sent = 0;   // the bytes of those frames
  // Serial: the queue was full and its oldest frame was discarded. UDP: EAGAIN or ENOBUFS.
  std::uint64_t frames_dropped_queue_full = 0;
  // UDP: no route yet, the send reported the peer's refusal, or (listening) no peer known yet.
  // Serial: the frame being written when the device went away (frames queued meanwhile wait
  // for it to return).
  std::uint64_t frames_dropped_link_down = 0;
  std::uint64_t frames_rejected = 0;  // empty or longer than kMaxLinkFrameBytes
  std::uint64_t frames_pending = 0;   // serial: in the queue or being written now
  std::uint64_t errors = 0;           // failed system calls: send, connect, write, poll, open
  // Serial: successful opens after a loss or a failed first open. UDP: connects that
  // succeeded after the network was not ready at open.
  std::uint64_t reconnects = 0;
  // Rises when the problem text changes, and at most about once a second while one problem
  // persists: log last_problem() when this moved, and the journal gets a rate-limited line.
  std::uint64_t problem_reports = 0;
  bool link_up = false;  // serial: device open; UDP: connected (listening: a peer known) and the last send succeeded
  std::uint64_t bytes_received = 0;    // by receive()
  std::uint64_t peer_changes = 0;      // UDP listening: times the reply address changed
};

class OutputLink {
 public:
  virtual ~OutputLink() = default;
  OutputLink() = default;
  OutputLink(const OutputLink&) = delete;
  OutputLink& operator=(const OutputLink&) = delete;

  // Hands one whole encoded frame to the transport. Returns at once; never throws. Frames are
  // never split or interleaved: the receiver sees each one whole or not at all. Call it from
  // one thread (the output thread); stats(), last_problem() and description() from any.
  virtual SendResult send(std::span<const std::uint8_t> frame) noexcept = 0;
  // As send(), for a frame whose delay matters more than the queue's order (a TIMESYNC
  // answer): a queueing transport writes it before the frames already waiting. May also be
  // called from the receiver thread.
  virtual SendResult send_urgent(std::span<const std::uint8_t> frame) noexcept { return send(frame); }
  // A transport that sends urgent frames ahead of queued ones calls this on each frame as it
  // leaves, in wire order, so that the sender can number the frames in that order (MAVLink's
  // sequence). Called on the transport's own thread; set it once, before sending.
  virtual void set_restamp(std::function<void(std::span<std::uint8_t> frame)> restamp) { (void)restamp; }
  virtual LinkStats stats() const = 0;
  // The most recent problem ("serial /dev/ttyUSB0: write failed: Input/output error (3
  // times)"); empty if there has been none. It stays after recovery: see LinkStats::link_up.
  virtual std::string last_problem() const = 0;
  virtual std::string description() const = 0;  // "udp 192.168.2.1:14550", for the start-up log

  // Waits up to timeout_ms for bytes from the far end and copies them into `into` (give room
  // for kMaxDatagramBytes: a datagram that does not fit is cut). Call it from one thread, the
  // link's receiver, never from the output thread; it never throws. A bounded timeout lets the
  // receiver notice shutdown promptly.
  virtual ReceiveResult receive(std::span<std::uint8_t> into, int timeout_ms) noexcept = 0;
  // UDP listening mode: from now on send() goes to the sender of the datagram receive() last
  // returned (call it once that datagram proved to hold a valid MAVLink frame). Elsewhere a no-op.
  virtual void reply_to_last_sender() noexcept {}
  // UDP listening mode: the current peer ("127.0.0.1:40123"), empty until one is known.
  // Elsewhere empty.
  virtual std::string peer() const { return {}; }
};

// The largest UDP payload: a receive buffer of this size never cuts a datagram.
inline constexpr std::size_t kMaxDatagramBytes = 65507;

struct UdpLinkOptions {
  // Sending to a fixed peer (udp://): IPv4 or IPv6 literal, or a host name (resolved once,
  // when the link opens). Listening (udpin://): the local address to bind, empty for any IPv4
  // address (0.0.0.0); "::" for any IPv6 address (and IPv4-mapped ones).
  std::string host;
  std::uint16_t port = 0;  // the peer's port, or (listening) the local port to bind
  std::uint16_t local_port = 0;  // fixed peer only. 0: any; set it when the peer only accepts a known source port
  // udpin://: bind host:port and reply to whoever sent the last valid MAVLink frame, as PX4 and
  // MAVSDK do on their UDP ports (PX4 SITL's offboard API port is 14540).
  bool listen = false;
};

// Supported rates (termios B* constants). Above 115200 check what the adapter and the flight
// controller's UART accept: 1500000 and 3000000 are not reachable on every USB-serial chip.
inline constexpr std::array<int, 12> kSupportedSerialBauds{
    57600, 115200, 230400, 460800, 500000, 576000, 921600, 1000000, 1152000, 1500000, 2000000, 3000000};
inline constexpr int kDefaultSerialBaud = 921600;
// Throws LinkError naming the rates above unless baud is one of them (for configuration checks).
void check_serial_baud(int baud);

struct SerialLinkOptions {
  // Prefer a /dev/serial/by-id/ name: it survives re-plugging, where /dev/ttyUSB0 may come
  // back as /dev/ttyUSB1. The link follows the name again at every re-open.
  std::string device_path;
  int baud = kDefaultSerialBaud;  // 8N1, no flow control
  // Frames waiting for the wire. When full the oldest is dropped: the newest odometry is worth
  // most. 64 frames is about 2 s at 30 Hz, the longest a stale estimate is still of any use.
  std::size_t queue_frames = 64;
};

using LinkOptions = std::variant<UdpLinkOptions, SerialLinkOptions>;

// udp://HOST:PORT, udp://[IPV6]:PORT, optionally ?local_port=N
// udpin://[ADDR]:PORT (udpin://:14540, udpin://0.0.0.0:14540, udpin://[::]:14540)
// serial:///dev/ttyUSB0[:BAUD], optionally ?queue_frames=N (the baud is a trailing ":DIGITS")
// Throws LinkError naming the URI and what is wrong (unknown scheme, missing host or port,
// port out of range, unsupported baud...).
LinkOptions parse_link_uri(const std::string& uri);

// Open a link. Throw LinkError for what waiting cannot fix: an unresolvable host name, a local
// port in use, a serial path that is a directory or not a terminal, no permission, a baud the
// driver refuses. A serial device that does not exist yet is not an error: see transport_serial.cpp.
std::unique_ptr<OutputLink> open_link(const LinkOptions& options);
std::unique_ptr<OutputLink> open_link(const std::string& uri);
std::unique_ptr<OutputLink> open_udp_link(const UdpLinkOptions& options);
std::unique_ptr<OutputLink> open_serial_link(const SerialLinkOptions& options);

// Whether a serial line can carry a message stream. 8N1 puts 10 bits on the wire per byte.
enum class CapacityVerdict {
  Ok,         // at most kSerialUtilisationWarning of the line
  NearLimit,  // fits, but with too little slack for other traffic and bursts
  Exceeded,   // more than the line can carry: the queue fills and frames are dropped
};
// The flight controller's other streams, USB-serial scheduling and bursts need slack.
inline constexpr double kSerialUtilisationWarning = 0.8;

struct SerialCapacity {
  double bits_per_s_needed = 0;
  double utilisation = 0;  // needed / baud
  CapacityVerdict verdict = CapacityVerdict::Ok;
  std::string message;  // one line for the start-up log
};

SerialCapacity serial_capacity(int baud, std::size_t bytes_per_message, double messages_per_s);

}  // namespace rgbdo
