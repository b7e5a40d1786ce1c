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
// A lost sensor is waited for by the capture thread (the feed's own re-open policy,
// sensor/reconnecting_feed.hpp); the pair spanning the gap is reported with status sensor_lost.
#include <atomic>
#include <cstdint>
#include <functional>
#include <string>

#include "rgbd_odometry/pipeline/pipeline_config.hpp"
#include "rgbd_odometry/runtime/runtime_config.hpp"
#include "rgbd_odometry/core/gyro.hpp"
#include "rgbd_odometry/io/frame_feed.hpp"
#include "rgbd_odometry/runtime/latency.hpp"
#include "rgbd_odometry/core/pair_output.hpp"

namespace rgbdo {

struct RealtimeStats {
  std::uint64_t frames = 0;    // processed
  std::uint64_t skipped = 0;   // replaced by a newer frame before processing could take them
  std::uint64_t without_depth = 0;  // colour frames the sensor gave up: no depth frame within 20 ms
  std::uint64_t pairs = 0;
  int sensor_losses = 0, reopens = 0;
  int dropped_by_sensor = 0;   // from the sensor's frame indices
  std::uint64_t stamp_not_increasing = 0;  // frames dropped: captured no later than the previous one
  std::uint64_t bridged_without_depth = 0;  // frames without depth dropped, the next paired across them
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
  RealtimePipeline(const PipelineConfig& config, const RuntimeConfig& runtime, FrameFeed& feed, OutputFn on_output,
                   MessageFn on_message, GyroFeed* gyro = nullptr);
  // Called on the output thread at least every 50 ms, frames or not (heartbeats, link news).
  void set_tick(std::function<void()> on_tick) { on_tick_ = std::move(on_tick); }

  // Runs until the feed ends, the sensor stays lost past sensor.reconnect_timeout_s, or
  // `stop` becomes true (then: within a second, every frame in hand is finished and output).
  // Throws ConfigError when runtime.cpu_affinity names a CPU this process may not use.
  RealtimeStats run(const std::atomic<bool>& stop);

 private:
  PipelineConfig config_;
  RuntimeConfig runtime_;
  FrameFeed& feed_;
  GyroFeed* gyro_;
  OutputFn on_output_;
  MessageFn on_message_;
  std::function<void()> on_tick_;
};

}  // namespace rgbdo
