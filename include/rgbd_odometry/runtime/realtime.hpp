#pragma once
// The real-time pipeline: capture, processing and output each on their own threads, joined
// by bounded queues allocated once.
//
//   capture --FrameMailbox--> extraction --(4 frame slots)--> estimation --(64 results)--> output
//
// Capture never waits on processing (a live frame not taken in time is replaced by the newer
// one, and counted); with runtime.processing_threads = 2 the feature extraction of frame k+1
// runs while frame k is matched, fitted and its covariance sampled. Output (logs, link,
// console) runs in order on its own thread, so a slow disk or terminal never stalls capture;
// if it falls 64 results behind, estimation waits, and the newest-frame rule absorbs it.
// A lost sensor is re-opened by the capture thread; the pair spanning the gap is reported
// with status sensor_lost.
#include <atomic>
#include <cstdint>
#include <functional>
#include <string>

#include "rgbd_odometry/core/config.hpp"
#include "rgbd_odometry/core/gyro.hpp"
#include "rgbd_odometry/sensor/frame_feed.hpp"
#include "rgbd_odometry/runtime/latency.hpp"
#include "rgbd_odometry/core/pair_result.hpp"

namespace rgbdo {

struct PairOutput {
  bool has_pair = false;                  // false for the very first frame
  PairResult result;                      // when has_pair
  std::int64_t t_frame_ns = 0;            // colour capture time of the newer frame (its source's timeline)
  std::int64_t t_depth_ns = 0;            // capture time of the depth image paired with it
  std::int64_t host_lead_ns = 0;          // see RgbdFrame
  std::int64_t t_frame_host_ns() const { return t_frame_ns - host_lead_ns; }  // as stamped in the pair
  std::int64_t t_capture_host_ns = 0;     // steady clock, see CapturedFrame
  int skipped = 0;                        // frames skipped between the pair's two frames
  double latency_ms = 0;                  // capture to hand-over to the outputs
  std::string frame_problem;              // the newer frame's failure, as the source put it
};

struct RealtimeStats {
  std::uint64_t frames = 0;    // processed
  std::uint64_t skipped = 0;   // replaced by a newer frame before the reader or processing could take them
  std::uint64_t pairs = 0;
  int sensor_losses = 0, reopens = 0;
  int dropped_by_sensor = 0;   // from the sensor's frame indices
  std::uint64_t stamp_not_increasing = 0;  // frames dropped: captured no later than the previous one
  LatencyHistogram latency;    // of pairs
  // Empty unless a thread failed (an exception): "<thread> thread: <what>". The run then
  // stopped as at a stop request; what was finished before was output.
  std::string failure;
};

class RealtimePipeline {
 public:
  using OutputFn = std::function<void(const PairOutput&)>;
  using MessageFn = std::function<void(const std::string&)>;
  // on_output gets every frame's result, in capture order; on_message the run's news (sensor
  // lost / back, periodic status). Both are called on the output thread only. gyro: the
  // autopilot's rates (live) or the recording's imu.txt, against which the frames' capture
  // latency is measured and applied (pipeline/capture_latency.hpp); null: the stamps stand.
  RealtimePipeline(const Config& config, FrameFeed& feed, OutputFn on_output, MessageFn on_message,
                   GyroFeed* gyro = nullptr);
  // Called on the output thread at least every 50 ms, frames or not (heartbeats, link news).
  void set_tick(std::function<void()> on_tick) { on_tick_ = std::move(on_tick); }

  // Runs until the feed ends, the sensor stays lost past sensor.reconnect_timeout_s, or
  // `stop` becomes true (then: within a second, every frame in hand is finished and output).
  // Throws ConfigError when runtime.cpu_affinity names a CPU this process may not use.
  RealtimeStats run(const std::atomic<bool>& stop);

 private:
  Config config_;
  FrameFeed& feed_;
  GyroFeed* gyro_;
  OutputFn on_output_;
  MessageFn on_message_;
  std::function<void()> on_tick_;
};

}  // namespace rgbdo
