#pragma once
// Maps a sensor's device timestamps onto the host's monotonic clock.
//
// The capture time, not the arrival time, is what the flight computer must get, and only the
// device knows it, on its own crystal. One offset fixed at the first frame keeps every interval
// exactly the device's (odometry divides by them) but lets the host times walk away with the
// crystal's error: 30 ppm is ~0.1 s per hour. So the mapping also follows the rate between the
// two clocks, measured on the lower envelope of the arrivals: the least transport delay seen in
// each window of device time is stable, so the slope of those minima is the clock skew. The
// mapping stays continuous (re-anchored at every change of rate): intervals change by the skew,
// parts per million, never by a jump.
//
// A rate further from the host's than a crystal can be (over 1000 ppm) is not followed: it is
// a device clock that runs at another speed on purpose (the virtual sensor at rate != 1 keeps
// the recording's times), reported by implausible_skew(). A recording played back is never
// followed (follow_rate false): it arrives at the reader's pace, which says nothing about
// any crystal, and its intervals must stay exactly the recorded ones.
//
// That timeline starts at the first frame's arrival, which is late by the transport delay
// and, at start-up, by however long the reader took to begin: every later frame would then be
// stamped after it arrived (measured: 225 of 239 pairs of a live replay). A capture cannot
// follow its arrival, so a frame mapped after its arrival proves the timeline that far ahead:
// lead_ns() is the most any frame has proved so far (it only grows, by steps, mostly in the
// first frames). Host capture time = timeline - lead. Intervals are taken on the timeline,
// never across a step of the lead.
#include <cstdint>

namespace rgbdo {

class DeviceClock {
 public:
  static constexpr std::int64_t kWindowNs = 5'000'000'000;  // of device time, per envelope point
  static constexpr double kMaxSkew = 1e-3;                  // beyond this, not a crystal's error
  // Each window's weight in the fit decays by this per window (~4 min of memory): a crystal's
  // rate wanders with its temperature.
  static constexpr double kForget = 0.98;

  explicit DeviceClock(bool follow_rate = true) : follow_rate_(follow_rate) {}

  // The timeline's time (host clock, continuous) of a frame captured at `device_ns` (device
  // clock) that arrived at `arrival_host_ns`.
  std::int64_t to_host(std::int64_t device_ns, std::int64_t arrival_host_ns);
  // How far the timeline runs ahead of the host clock, as proved by the frames so far (>= 0).
  std::int64_t lead_ns() const { return lead_ns_; }

  double skew() const { return skew_; }  // host seconds per device second, minus 1
  bool implausible_skew() const { return implausible_; }

 private:
  std::int64_t map(std::int64_t device_ns, std::int64_t arrival_host_ns);

  bool follow_rate_ = true, started_ = false;
  std::int64_t anchor_device_ns_ = 0, anchor_host_ns_ = 0;
  std::int64_t lead_ns_ = 0;
  double skew_ = 0;
  bool implausible_ = false;
  // The current window: its start and its least (arrival - device) so far.
  std::int64_t window_start_ns_ = 0, window_min_ns_ = 0, window_min_at_ns_ = 0;
  // Weighted least squares of the windows' minima against device time, relative to the first frame.
  int windows_ = 0;
  double n_ = 0, sum_t_ = 0, sum_m_ = 0, sum_tt_ = 0, sum_tm_ = 0;
  std::int64_t origin_device_ns_ = 0, origin_offset_ns_ = 0;
};

}  // namespace rgbdo
