#pragma once
// Our side of MAVLink TIMESYNC (#111, time synchronisation protocol v2): the autopilot's clock
// offset and the round-trip time, estimated from its answers to our requests.
//
// A request carries our clock in ts1; the answer adds the autopilot's clock at answering in
// tc1. With the round trip rtt = now - ts1 split evenly, one sample of the offset
// (autopilot clock - ours) is tc1 - (ts1 + now) / 2, wrong by at most rtt / 2 (all of the
// delay on one side).
//
// The filter is NTP's clock filter, not PX4's double exponential smoothing: of the last
// kWindow samples, the one with the shortest round trip is the one least delayed by queues
// (a serial line busy with odometry, a loaded CPU), and its offset is the estimate, with
// rtt / 2 as its stated error bound. It is usable from the first answer, needs no gain
// schedule and does not lag a step. What it does not model is drift between the clocks: a
// sample is at most kWindow request periods old (8 s at 1 Hz), which at a crystal's 50 ppm is
// 0.4 ms; the window is short to keep that small.
//
// Answers that are not to one of our recent requests (ts1 unknown: another system's request,
// a duplicate, a stale reply), whose round trip exceeds max_rtt_ns or whose tc1 is so far from
// our clock that the offset does not fit 64 bits are not used.
// Not thread-safe: the owner guards it.
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>

namespace rgbdo {

struct TimesyncEstimate {
  bool valid = false;          // at least one sample
  std::int64_t offset_ns = 0;  // autopilot clock - our clock
  std::int64_t rtt_ns = 0;     // round trip of the sample the estimate comes from (error <= rtt/2)
  std::uint64_t samples = 0;   // answers used, since the start (or the last reset)
  std::uint64_t rejected = 0;  // answers not to our requests, too slow, or off any clock
};

class TimesyncEstimator {
 public:
  static constexpr std::size_t kWindow = 8;
  static constexpr std::size_t kOutstanding = 16;  // requests whose answer is still accepted

  explicit TimesyncEstimator(std::int64_t max_rtt_ns) : max_rtt_ns_(max_rtt_ns) {}

  void note_request(std::int64_t ts1_ns);
  enum class Answer { Used, NotOurs, TooSlow, ClockOutOfRange };
  // An answer (tc1 != 0) that arrived at now_ns, our clock.
  Answer add_answer(std::int64_t tc1_ns, std::int64_t ts1_ns, std::int64_t now_ns);
  TimesyncEstimate estimate() const;
  // Our clock's time_ns on the autopilot's clock, once there is an estimate (and the result
  // fits 64 bits).
  std::optional<std::int64_t> to_autopilot_ns(std::int64_t time_ns) const;
  // A different autopilot: its clock has nothing to do with the old one's.
  void reset();

 private:
  struct Sample {
    std::int64_t offset_ns = 0, rtt_ns = 0;
  };
  std::int64_t max_rtt_ns_;
  std::array<std::int64_t, kOutstanding> outstanding_{};  // ts1 of recent requests, 0: free
  std::size_t next_outstanding_ = 0;
  std::array<Sample, kWindow> window_{};
  std::size_t window_size_ = 0, next_sample_ = 0;
  std::uint64_t samples_ = 0, rejected_ = 0;
};

}  // namespace rgbdo
