#pragma once
// The flight-computer link, both ways. Out: each pair result becomes MAVLink 2 ODOMETRY
// (and/or ArduPilot's VISION_POSITION_DELTA) on the configured link, with a HEARTBEAT every
// second, from the pipeline's output thread, which it never blocks (the link queues or drops,
// and says so). In: a receiver thread of its own reads the same socket or serial port, follows
// the autopilot's HEARTBEAT (autopilot_watch.hpp), answers its TIMESYNC requests at once (so
// PX4 can map our capture times onto its clock) and measures the autopilot's clock offset with
// requests of ours (timesync.hpp). It asks the autopilot for its ATTITUDE at
// link.attitude_rate_hz (MAV_CMD_SET_MESSAGE_INTERVAL) and hands its rates, on our clock, to
// the odometry's capture-latency estimate (gyro()).
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "rgbd_odometry/core/camera_mount.hpp"
#include "rgbd_odometry/link/link_config.hpp"
#include "rgbd_odometry/link/autopilot_gyro.hpp"
#include "rgbd_odometry/link/autopilot_watch.hpp"
#include "rgbd_odometry/link/mavlink.hpp"
#include "rgbd_odometry/link/mavlink_odometry.hpp"
#include "rgbd_odometry/link/mavlink_parser.hpp"
#include "rgbd_odometry/link/timesync.hpp"
#include "rgbd_odometry/link/transport.hpp"

namespace rgbdo {

// What came back over the link.
struct LinkReceiveStats {
  mavlink::ParserCounts parser;
  AutopilotState autopilot;
  TimesyncEstimate timesync;
  std::uint64_t timesync_requests_answered = 0;  // the autopilot's requests we answered
  std::uint64_t timesync_requests_sent = 0;      // ours
};

class FlightLink {
 public:
  // Opens link.uri and starts receiving; throws LinkError naming the problem (a bad device path, say).
  FlightLink(const LinkConfig& config, const BodyConfig& body);
  ~FlightLink();  // stops the receiver (within one receive timeout)
  FlightLink(const FlightLink&) = delete;
  FlightLink& operator=(const FlightLink&) = delete;

  void send_pair(const PairResult& pair);  // status SensorLost marks a reset of the pose
  // The 1 Hz heartbeat, our TIMESYNC requests and the link's news; call often (the output
  // thread's tick, at least every 50 ms).
  void tick(std::int64_t now_ns);
  // What to tell the user at start: where it sends, what it listens for, whether a serial
  // line can carry it.
  std::string startup_report() const;
  // The next item of news (a link problem, an autopilot appearing, going or changing, a new
  // UDP peer, the first clock offset), each once; empty when there is none. Call from the
  // thread that calls tick(), after it, until it returns empty.
  std::string news();
  // One line for the periodic status: the autopilot (type, ids, up or gone, time since its
  // last heartbeat), the clock offset and round trip, the peer, what was received. Any thread.
  std::string status_line() const;
  LinkStats stats() const { return link_->stats(); }
  // Pairs whose message was held back: their capture time was not after the last one sent.
  std::uint64_t held_back() const { return held_back_; }
  LinkReceiveStats receive_stats() const;
  // The followed autopilot's ATTITUDE rates on our clock, for the capture latency (any thread).
  AutopilotGyro& gyro() { return gyro_; }
  // Our clock's time_ns (steady_now_ns) on the autopilot's clock, once measured: for a
  // consumer that needs a message stamped in the autopilot's time.
  std::optional<std::int64_t> to_autopilot_time_ns(std::int64_t time_ns) const;

 private:
  template <typename Message>
  void send_message(const Message& message);
  void receive_loop();
  // One checked frame that arrived at now_ns; true when it came from a system we follow.
  // sender_confirmed: whether the datagram's sender was already made the peer (UDP listening).
  bool handle(const mavlink::ReceivedFrame& frame, std::int64_t now_ns, bool& sender_confirmed);
  void note_changes(std::int64_t now_ns);
  void send_origin(std::int64_t now_ns);  // link.ekf_origin, while sends are due
  void level_local_frame();  // at the first good pair: from the autopilot's latest ATTITUDE
  void ask_attitude_rate(std::int64_t now_ns);  // MAV_CMD_SET_MESSAGE_INTERVAL, until acknowledged
  double advised_ev_delay_ms(const TimesyncEstimate& offset) const;

  LinkConfig config_;
  LinkOptions options_;  // parsed once: the link is opened from it
  std::unique_ptr<OutputLink> link_;
  OdometryMessageBuilder builder_;
  std::int64_t timesync_period_ns_ = 0;  // 0: we send no requests
  std::optional<GeoPoint> origin_;       // link.ekf_origin
  bool receiver_realtime_ = false;       // the receiver thread got SCHED_FIFO

  // Output thread and receiver both send; one framer keeps the sequence numbers in wire
  // order. Held only to encode one frame and hand it to the link (which never waits).
  std::mutex send_mutex_;
  mavlink::Framer framer_;
  mavlink::FrameBuffer buffer_{};
  std::uint8_t wire_sequence_ = 0;  // a reordering transport's thread's own (set_restamp)

  // Shared state, under state_mutex_: held only for the bookkeeping of one frame.
  mutable std::mutex state_mutex_;
  AutopilotWatch watch_;
  TimesyncEstimator timesync_;
  mavlink::ParserCounts parser_counts_;
  struct HeardAttitude {
    double roll_rad = 0, pitch_rad = 0;
    std::int64_t heard_ns = 0;  // 0: none heard
  } attitude_;  // the followed autopilot's latest ATTITUDE
  std::uint64_t answered_ = 0, requests_sent_ = 0;
  std::optional<std::uint8_t> interval_result_;  // the autopilot's COMMAND_ACK to our interval request
  AutopilotGyro gyro_;

  // The receiver thread's own.
  mavlink::FrameParser parser_;
  std::vector<std::uint8_t> receive_buffer_;
  std::atomic<bool> stop_{false};
  std::thread receiver_;

  // The output thread's own (tick, news).
  std::int64_t next_heartbeat_ns_ = 0, next_request_ns_ = 0;
  std::uint64_t problems_seen_ = 0, peer_changes_seen_ = 0;
  AutopilotState reported_;
  bool reported_offset_ = false, warned_round_trip_ = false;
  int origin_sends_left_ = 0;
  int interval_requests_left_ = 0;  // MAV_CMD_SET_MESSAGE_INTERVAL tries left for this autopilot
  std::int64_t next_interval_request_ns_ = 0;
  bool interval_reported_ = false;
  std::int64_t next_origin_ns_ = 0;
  std::atomic<std::uint64_t> origins_sent_{0};  // read by status_line() from any thread
  std::vector<std::string> news_;
  // The output thread's own (send_pair).
  std::int64_t last_time_usec_ = -1;
  std::uint64_t held_back_ = 0;
  // Capture to hand-over, smoothed; < 0 until the first good pair. Read by status_line().
  std::atomic<double> output_latency_ms_{-1};
};

}  // namespace rgbdo
