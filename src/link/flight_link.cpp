#include "rgbd_odometry/link/flight_link.hpp"

#include <pthread.h>

#include <cmath>
#include <cstdio>
#include <iomanip>
#include <sstream>

#include "rgbd_odometry/core/clock.hpp"

namespace rgbdo {
namespace {

constexpr std::int64_t kHeartbeatPeriodNs = 1'000'000'000;
// The longest the receiver waits in receive() before looking at stop_ again.
constexpr int kReceivePoll_ms = 100;
constexpr double kDegToRad = M_PI / 180.0;
constexpr double kFrameRateHz = 30.0;  // the sensor's rate, for the serial capacity check
// The EKF origin is sent this many times, a second apart, each time an autopilot is heard or
// comes back (it may have rebooted and lost it): a lost datagram costs one copy, not the flight.
constexpr int kOriginRepeats = 5;
constexpr std::int64_t kOriginPeriodNs = 1'000'000'000;
// MAV_CMD_SET_MESSAGE_INTERVAL is sent until acknowledged, this many times a second apart.
constexpr int kIntervalRequests = 5;
constexpr std::int64_t kIntervalRequestPeriodNs = 1'000'000'000;
// PX4 uses a TIMESYNC round trip only below this (Timesync.hpp MAX_RTT_SAMPLE, 10 ms).
constexpr std::int64_t kPx4MaxRttNs = 10'000'000;
// An ATTITUDE older than this at the first pair says nothing about the vehicle then (PX4 streams
// it at 20-50 Hz in Onboard mode, ArduPilot at its SRn_EXTRA1 rate).
constexpr std::int64_t kAttitudeFreshNs = 500'000'000;
// The receiver answers TIMESYNC requests: above the pipeline's threads (SCHED_OTHER) so that
// an answer never waits for a busy core (measured: up to 7 ms on an idle 2-core x86 without).
constexpr int kReceiverPriority = 10;

MavlinkOdometryConfig message_config(const LinkConfig& c, const BodyConfig& body) {
  MavlinkOdometryConfig m;
  m.extrinsic = extrinsic_from(body);
  m.quality_sigma_fail_m = c.quality_sigma_fail_m;
  m.velocity_error_min_mps = c.velocity_error_min_mps;
  m.velocity_error_max_mps = c.velocity_error_max_mps;
  m.delta_min_interval_s = c.delta_min_interval_ms * 1e-3;
  return m;
}

std::string seconds_ago(std::int64_t now_ns, std::int64_t then_ns) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f s", static_cast<double>(now_ns - then_ns) * 1e-9);
  return text;
}

std::string describe(const AutopilotIdentity& id) {
  std::string s = autopilot_name(id.autopilot);
  if (s == "autopilot") s += " type " + std::to_string(id.autopilot);
  return s + " (system " + std::to_string(id.system_id) + ", component " + std::to_string(id.component_id) + ")";
}

// "+1234.567890123 s (round trip 0.41 ms, 57 samples)"
std::string describe(const TimesyncEstimate& e) {
  char text[96];
  const long long s = e.offset_ns / 1'000'000'000, ns = std::llabs(e.offset_ns % 1'000'000'000);
  std::snprintf(text, sizeof text, "%s%lld.%09lld s (round trip %.2f ms, %llu samples)",
                e.offset_ns < 0 && s == 0 ? "-" : (e.offset_ns >= 0 ? "+" : ""), s, ns,
                static_cast<double>(e.rtt_ns) * 1e-6, static_cast<unsigned long long>(e.samples));
  return text;
}

// A TIMESYNC's target fields name us, or nobody in particular (0: broadcast, a v1 sender).
bool addressed_to(const mavlink::Timesync& m, std::uint8_t system_id, std::uint8_t component_id) {
  return (m.target_system == 0 || m.target_system == system_id) &&
         (m.target_component == 0 || m.target_component == component_id);
}

std::int32_t degrees_e7(double degrees) { return static_cast<std::int32_t>(std::llround(degrees * 1e7)); }

std::string describe(const GeoPoint& origin) {
  char text[96];
  std::snprintf(text, sizeof text, "%.7f, %.7f, %.3f m", origin.latitude_deg, origin.longitude_deg, origin.altitude_m);
  return text;
}

}  // namespace

FlightLink::FlightLink(const LinkConfig& config, const BodyConfig& body)
    : config_(config), options_(parse_link_uri(config.uri)), link_(open_link(options_)),
      builder_(message_config(config, body)),
      timesync_period_ns_(config.timesync_rate_hz > 0 ? seconds_to_ns(1.0 / config.timesync_rate_hz) : 0),
      origin_(parse_ekf_origin(config.ekf_origin)),
      framer_(static_cast<std::uint8_t>(config.system_id), mavlink::kMavCompIdVisualInertialOdometry),
      watch_(static_cast<std::uint8_t>(config.autopilot_system_id), static_cast<std::uint8_t>(config.system_id),
             mavlink::kMavCompIdVisualInertialOdometry, seconds_to_ns(config.autopilot_timeout_s)),
      timesync_(seconds_to_ns(config.timesync_max_rtt_ms * 1e-3)),
      receive_buffer_(kMaxDatagramBytes) {
  problems_seen_ = link_->stats().problem_reports;  // what is wrong at start is in startup_report()
  // Serial sends TIMESYNC answers ahead of queued frames: number every frame as it leaves, so
  // that the sequence is the wire's order (the transport's thread is the only caller).
  link_->set_restamp([this](std::span<std::uint8_t> frame) { (void)mavlink::restamp_sequence(frame, wire_sequence_++); });
  receiver_ = std::thread([this] { receive_loop(); });
  sched_param priority{};
  priority.sched_priority = kReceiverPriority;
  receiver_realtime_ = pthread_setschedparam(receiver_.native_handle(), SCHED_FIFO, &priority) == 0;
}

FlightLink::~FlightLink() {
  stop_ = true;
  receiver_.join();
}

template <typename Message>
void FlightLink::send_message(const Message& message) {
  std::lock_guard lock(send_mutex_);
  (void)link_->send(std::span<const std::uint8_t>(buffer_.data(), framer_.encode(message, buffer_)));
}

void FlightLink::send_pair(const PairResult& pair) {
  if (pair.frame_dropped) return;  // a dropped frame: the next pair carries the motion
  if (pair.status == Status::SensorLost) builder_.note_sensor_reset();
  if (!builder_.has_pose() && pair.status == Status::Ok) level_local_frame();
  builder_.add(pair);
  // An autopilot keeps its samples in time order (PX4's ring buffer, EKF3's): a message not
  // after the last one sent (a host clock step) is held back and counted, never sent.
  const auto time_usec = static_cast<std::int64_t>(pair.t_curr_ns / 1000);
  if (time_usec <= last_time_usec_) {
    ++held_back_;
    return;
  }
  last_time_usec_ = time_usec;
  if (pair.status == Status::Ok) {
    // Capture to hand-over, for the EKF2_EV_DELAY advice: a slow average (a few seconds).
    const double latency_ms = static_cast<double>(steady_now_ns() - pair.t_curr_ns) * 1e-6;
    const double smoothed = output_latency_ms_.load();
    if (latency_ms > 0 && latency_ms < 1000)
      output_latency_ms_ = smoothed < 0 ? latency_ms : 0.95 * smoothed + 0.05 * latency_ms;
  }
  if (config_.odometry) {
    if (const auto odometry = builder_.odometry()) send_message(*odometry);
  }
  if (config_.vision_position_delta) {
    if (const auto delta = builder_.vision_position_delta()) send_message(*delta);
  }
}

void FlightLink::receive_loop() {
  pthread_setname_np(pthread_self(), "rgbdo-mavlink-rx");  // for top -H on the vehicle
  while (!stop_.load(std::memory_order_relaxed)) {
    const ReceiveResult got = link_->receive(receive_buffer_, kReceivePoll_ms);
    if (got.bytes == 0) continue;
    const std::int64_t now_ns = steady_now_ns();
    bool sender_confirmed = !got.datagram;  // serial: there is only one far end
    const auto on_frame = [&](const mavlink::ReceivedFrame& frame) { handle(frame, now_ns, sender_confirmed); };
    parser_.feed(std::span<const std::uint8_t>(receive_buffer_.data(), got.bytes), on_frame);
    // A datagram holds whole frames: what is left unfinished was a false start, never continued.
    if (got.datagram) parser_.end_datagram(on_frame);
    std::lock_guard lock(state_mutex_);
    parser_counts_ = parser_.counts();
  }
}

bool FlightLink::handle(const mavlink::ReceivedFrame& frame, std::int64_t now_ns, bool& sender_confirmed) {
  const auto own_system = static_cast<std::uint8_t>(config_.system_id);
  const std::uint8_t own_component = mavlink::kMavCompIdVisualInertialOdometry;
  mavlink::Timesync request;
  bool answer = false;
  {
    std::lock_guard lock(state_mutex_);
    const AutopilotIdentity before = watch_.state(now_ns).identity;
    if (!watch_.accept(frame, now_ns)) return false;
    if (!sender_confirmed) {  // UDP listening: a valid frame makes its sender the peer, before any answer to it
      link_->reply_to_last_sender();
      sender_confirmed = true;
    }
    if (watch_.state(now_ns).identity != before) {  // another autopilot, another clock
      timesync_.reset();
      gyro_.clear();
      interval_result_.reset();
    }
    const AutopilotIdentity followed = watch_.state(now_ns).identity;
    const bool from_autopilot = frame.sysid == followed.system_id && frame.compid == followed.component_id;
    if (frame.msgid == mavlink::Attitude::kId && from_autopilot) {  // the autopilot's own, not a gimbal's
      const mavlink::Attitude a = mavlink::unpack_attitude(frame.payload);
      if (std::isfinite(a.roll) && std::isfinite(a.pitch)) attitude_ = {a.roll, a.pitch, now_ns};
      const TimesyncEstimate offset = timesync_.estimate();
      gyro_.add(a.time_boot_ms, a.rollspeed, a.pitchspeed, a.yawspeed,
                offset.valid ? std::optional<std::int64_t>(offset.offset_ns) : std::nullopt);
      return true;
    }
    if (frame.msgid == mavlink::CommandAck::kId && from_autopilot) {
      const mavlink::CommandAck ack = mavlink::unpack_command_ack(frame.payload);
      if (ack.command == mavlink::kMavCmdSetMessageInterval &&
          (ack.target_system == 0 || ack.target_system == own_system))
        interval_result_ = ack.result;
      return true;
    }
    if (frame.msgid != mavlink::Timesync::kId) return true;
    const mavlink::Timesync m = mavlink::unpack_timesync(frame.payload);
    if (!addressed_to(m, own_system, own_component)) return true;
    if (m.tc1 == 0) {
      request = m;
      answer = true;
    } else {
      (void)timesync_.add_answer(m.tc1, m.ts1, now_ns);
    }
  }
  if (answer) {
    // At once, from this thread: the requester's round trip is what it measures its offset
    // with, and it discards long ones (PX4: 10 ms).
    std::lock_guard lock(send_mutex_);
    mavlink::Timesync reply;
    reply.tc1 = steady_now_ns();  // the clock the capture times are on
    reply.ts1 = request.ts1;
    reply.target_system = frame.sysid;
    reply.target_component = frame.compid;
    (void)link_->send_urgent(std::span<const std::uint8_t>(buffer_.data(), framer_.encode(reply, buffer_)));
    std::lock_guard state_lock(state_mutex_);
    ++answered_;
  }
  return true;
}

void FlightLink::tick(std::int64_t now_ns) {
  if (now_ns >= next_heartbeat_ns_) {
    next_heartbeat_ns_ = now_ns + kHeartbeatPeriodNs;
    send_message(builder_.heartbeat());
  }
  if (timesync_period_ns_ > 0 && now_ns >= next_request_ns_) {
    mavlink::Timesync request;
    bool ask = false;
    {
      std::lock_guard lock(state_mutex_);
      const AutopilotState ap = watch_.state(now_ns);
      if (ap.up) {  // no requests into a void, nor to a ground station
        request.ts1 = steady_now_ns();
        request.target_system = ap.identity.system_id;
        request.target_component = ap.identity.component_id;
        timesync_.note_request(request.ts1);  // before it can be answered
        ++requests_sent_;
        ask = true;
      }
    }
    if (ask) {
      send_message(request);
      next_request_ns_ = now_ns + timesync_period_ns_;
    }
  }
  note_changes(now_ns);
  send_origin(now_ns);
  ask_attitude_rate(now_ns);
}

void FlightLink::ask_attitude_rate(std::int64_t now_ns) {
  if (config_.attitude_rate_hz <= 0) return;
  std::optional<std::uint8_t> result;
  AutopilotIdentity target;
  {
    std::lock_guard lock(state_mutex_);
    result = interval_result_;
    const AutopilotState ap = watch_.state(now_ns);
    if (!ap.up) return;
    target = ap.identity;
  }
  if (result) {
    if (!interval_reported_) {
      interval_reported_ = true;
      char text[200];
      if (*result == mavlink::kMavResultAccepted)
        std::snprintf(text, sizeof text, "ATTITUDE at %.0f Hz accepted by the autopilot (its rates time the frames)",
                      config_.attitude_rate_hz);
      else
        std::snprintf(text, sizeof text,
                      "ATTITUDE at %.0f Hz refused by the autopilot (MAV_RESULT %d): the rates it streams anyway are "
                      "used (ArduPilot: SRn_EXTRA1)",
                      config_.attitude_rate_hz, *result);
      news_.push_back(text);
    }
    return;
  }
  if (interval_requests_left_ <= 0 || now_ns < next_interval_request_ns_) return;
  mavlink::CommandLong command;
  command.command = mavlink::kMavCmdSetMessageInterval;
  command.param[0] = static_cast<float>(mavlink::Attitude::kId);
  command.param[1] = static_cast<float>(1e6 / config_.attitude_rate_hz);  // interval, microseconds
  command.target_system = target.system_id;
  command.target_component = target.component_id;
  command.confirmation = static_cast<std::uint8_t>(kIntervalRequests - interval_requests_left_);
  send_message(command);
  if (--interval_requests_left_ == 0 && !interval_reported_) {
    interval_reported_ = true;
    // snprintf, not operator+: GCC 12 on armhf warns falsely about std::string's insert there.
    char text[160];
    std::snprintf(text, sizeof text,
                  "no answer to %d requests for ATTITUDE (MAV_CMD_SET_MESSAGE_INTERVAL): the rates it streams anyway "
                  "are used",
                  kIntervalRequests);
    news_.push_back(text);
  }
  next_interval_request_ns_ = now_ns + kIntervalRequestPeriodNs;
}

void FlightLink::level_local_frame() {
  HeardAttitude a;
  {
    std::lock_guard lock(state_mutex_);
    a = attitude_;
  }
  char text[300];
  if (a.heard_ns > 0 && steady_now_ns() - a.heard_ns < kAttitudeFreshNs &&
      builder_.level_initial_attitude(a.roll_rad, a.pitch_rad)) {
    std::snprintf(text, sizeof text,
                  "local frame levelled with the autopilot's attitude at the first pair: roll %.2f deg, pitch %.2f deg "
                  "(%.9g rad, %.9g rad)",
                  a.roll_rad / kDegToRad, a.pitch_rad / kDegToRad, a.roll_rad, a.pitch_rad);
  } else {
    std::snprintf(text, sizeof text,
                  "no ATTITUDE from the autopilot at the first pair: the local frame is the body frame at the first "
                  "frame, level only if the vehicle was");
  }
  news_.push_back(text);
}

void FlightLink::send_origin(std::int64_t now_ns) {
  if (!origin_ || origin_sends_left_ <= 0 || now_ns < next_origin_ns_) return;
  std::uint8_t target = 0;
  {
    std::lock_guard lock(state_mutex_);
    const AutopilotState ap = watch_.state(now_ns);
    if (!ap.up) return;
    target = ap.identity.system_id;
  }
  mavlink::SetGpsGlobalOrigin origin;
  origin.latitude_deg_e7 = degrees_e7(origin_->latitude_deg);
  origin.longitude_deg_e7 = degrees_e7(origin_->longitude_deg);
  origin.altitude_mm = static_cast<std::int32_t>(std::llround(origin_->altitude_m * 1e3));
  origin.target_system = target;
  send_message(origin);
  // Home at the origin, level: ArduPilot arms and returns there (vision_to_mavros does the same).
  mavlink::SetHomePosition home;
  home.latitude_deg_e7 = origin.latitude_deg_e7;
  home.longitude_deg_e7 = origin.longitude_deg_e7;
  home.altitude_mm = origin.altitude_mm;
  home.target_system = target;
  send_message(home);
  ++origins_sent_;
  if (origin_sends_left_-- == kOriginRepeats)
    news_.push_back("EKF origin " + describe(*origin_) + " sent to system " + std::to_string(target) +
                    " (SET_GPS_GLOBAL_ORIGIN and SET_HOME_POSITION, " + std::to_string(kOriginRepeats) +
                    " times a second apart)");
  next_origin_ns_ = now_ns + kOriginPeriodNs;
}

void FlightLink::note_changes(std::int64_t now_ns) {
  AutopilotState ap;
  TimesyncEstimate offset;
  {
    std::lock_guard lock(state_mutex_);
    ap = watch_.state(now_ns);
    offset = timesync_.estimate();
  }
  // The peer first: a listening link learns it from the frame that also announced the autopilot.
  const LinkStats st = link_->stats();
  if (st.peer_changes != peer_changes_seen_) {
    peer_changes_seen_ = st.peer_changes;
    news_.push_back("replying to " + link_->peer());
  }
  if (ap.known && (!reported_.known || ap.identity != reported_.identity)) {
    news_.push_back("autopilot " + describe(ap.identity) + " heard" +
                    (reported_.known ? " (was " + describe(reported_.identity) + ")" : ""));
    reported_offset_ = false;
  }
  if (ap.known && ap.up != reported_.up) {
    news_.push_back(ap.up ? "autopilot " + describe(ap.identity) + " up"
                          : "autopilot " + describe(ap.identity) + " gone: nothing heard from it for " +
                                seconds_ago(now_ns, ap.last_frame_ns));
  }
  if (ap.known && ap.up && (!reported_.up || ap.identity != reported_.identity)) {
    origin_sends_left_ = kOriginRepeats;  // heard, or back (perhaps rebooted): the origin again
    next_origin_ns_ = now_ns;
    interval_requests_left_ = kIntervalRequests;  // and the ATTITUDE rate asked for again
    next_interval_request_ns_ = now_ns;
    interval_reported_ = false;
    std::lock_guard lock(state_mutex_);
    interval_result_.reset();
  }
  reported_ = ap;
  if (offset.valid && !reported_offset_) {
    news_.push_back("clock offset to the autopilot " + describe(offset));
    reported_offset_ = true;
  }
  if (offset.valid && offset.rtt_ns >= kPx4MaxRttNs && ap.identity.autopilot == mavlink::kMavAutopilotPx4 &&
      !warned_round_trip_) {
    // Our own requests' best round trip is the link's: PX4's to us is no shorter.
    warned_round_trip_ = true;
    char text[400];
    std::snprintf(text, sizeof text,
                  "WARNING: TIMESYNC round trip %.1f ms, over PX4's 10 ms limit: PX4 uses none of these round trips, "
                  "never converges and stamps every ODOMETRY with its arrival time. Set EKF2_EV_DELAY to about %.0f ms "
                  "(capture to output %.0f ms + half the round trip), or use a faster link.",
                  static_cast<double>(offset.rtt_ns) * 1e-6, advised_ev_delay_ms(offset), std::max(0.0, output_latency_ms_.load()));
    news_.push_back(text);
  }
  if (st.problem_reports != problems_seen_) {
    problems_seen_ = st.problem_reports;
    news_.push_back(link_->last_problem());
  }
}

double FlightLink::advised_ev_delay_ms(const TimesyncEstimate& offset) const {
  return std::max(0.0, output_latency_ms_.load()) + static_cast<double>(offset.rtt_ns) * 1e-6 / 2;
}

std::string FlightLink::startup_report() const {
  std::ostringstream s;
  s << "MAVLink 2 to " << link_->description() << " as system " << config_.system_id << " component "
    << static_cast<int>(mavlink::kMavCompIdVisualInertialOdometry) << ":" << (config_.odometry ? " ODOMETRY" : "")
    << (config_.vision_position_delta ? " VISION_POSITION_DELTA" : "") << " per frame pair, HEARTBEAT at 1 Hz";
  s << "\nlistening on the same link: following the HEARTBEAT of "
    << (config_.autopilot_system_id == 0 ? std::string("the first autopilot heard")
                                         : "the autopilot of system " + std::to_string(config_.autopilot_system_id))
    << " (gone after " << config_.autopilot_timeout_s << " s of silence), answering its TIMESYNC requests, ";
  if (timesync_period_ns_ > 0)
    s << "asking its clock offset at " << config_.timesync_rate_hz << " Hz while it is up";
  else
    s << "not asking its clock offset (link.timesync_rate_hz 0)";
  if (origin_) s << "; EKF origin " << describe(*origin_) << " for the autopilot once heard";
  if (!receiver_realtime_)
    s << "\nthe receiver runs at normal priority (no CAP_SYS_NICE or RLIMIT_RTPRIO): a busy CPU can delay TIMESYNC "
         "answers past PX4's 10 ms";
  s << "\n" << status_line();
  if (const auto* serial = std::get_if<SerialLinkOptions>(&options_)) {
    // Wire bytes per pair: each message's full payload plus 12 bytes of framing.
    const std::size_t bytes = (config_.odometry ? mavlink::Odometry::kPayloadBytes + 12 : 0) +
                              (config_.vision_position_delta ? mavlink::VisionPositionDelta::kPayloadBytes + 12 : 0);
    s << "\n" << serial_capacity(serial->baud, bytes, kFrameRateHz).message;
  }
  if (!link_->stats().link_up && !link_->last_problem().empty()) s << "\nnot up yet: " << link_->last_problem();
  return s.str();
}

std::string FlightLink::news() {
  if (news_.empty()) return {};
  std::string item = std::move(news_.front());
  news_.erase(news_.begin());
  return item;
}

LinkReceiveStats FlightLink::receive_stats() const {
  LinkReceiveStats r;
  std::lock_guard lock(state_mutex_);
  r.parser = parser_counts_;
  r.autopilot = watch_.state(steady_now_ns());
  r.timesync = timesync_.estimate();
  r.timesync_requests_answered = answered_;
  r.timesync_requests_sent = requests_sent_;
  return r;
}

std::optional<std::int64_t> FlightLink::to_autopilot_time_ns(std::int64_t time_ns) const {
  std::lock_guard lock(state_mutex_);
  return timesync_.to_autopilot_ns(time_ns);
}

std::string FlightLink::status_line() const {
  const std::int64_t now_ns = steady_now_ns();
  const LinkReceiveStats r = receive_stats();
  const AutopilotState& ap = r.autopilot;
  std::ostringstream s;
  if (!ap.known) {
    s << "no autopilot heard";
  } else if (ap.up) {
    s << "autopilot " << describe(ap.identity) << " up, last heartbeat " << seconds_ago(now_ns, ap.last_heartbeat_ns)
      << " ago";
  } else {
    s << "autopilot " << describe(ap.identity) << " GONE: nothing heard for " << seconds_ago(now_ns, ap.last_frame_ns)
      << ", last heartbeat " << seconds_ago(now_ns, ap.last_heartbeat_ns) << " ago";
  }
  if (ap.known) {
    if (r.timesync.valid)
      s << "; clock offset " << describe(r.timesync);
    else
      s << "; clock offset " << (timesync_period_ns_ > 0 ? "not measured yet" : "not asked");
    if (r.timesync.valid && r.timesync.rtt_ns >= kPx4MaxRttNs && ap.identity.autopilot == mavlink::kMavAutopilotPx4)
      s << " OVER PX4's 10 ms: set EKF2_EV_DELAY " << std::lround(advised_ev_delay_ms(r.timesync)) << " ms";
    s << ", " << r.timesync_requests_answered << " of its TIMESYNC requests answered";
    if (origin_) s << ", EKF origin sent " << origins_sent_ << " times";
    const AutopilotGyro::Counts g = gyro_.counts();
    s << ", " << g.received << " ATTITUDE rates (" << g.unmapped << " before the clock offset)";
  }
  if (const std::string peer = link_->peer(); !peer.empty()) s << "; peer " << peer;
  if (std::holds_alternative<UdpLinkOptions>(options_) && std::get<UdpLinkOptions>(options_).listen && link_->peer().empty())
    s << "; no peer yet";
  s << "; received " << r.parser.frames_ok << " frames (" << r.parser.crc_errors << " bad checksums, "
    << r.parser.unknown_ids << " other messages, " << r.parser.bytes_discarded << " bytes of noise, "
    << ap.ignored_frames << " from other systems)";
  return s.str();
}

}  // namespace rgbdo
