#include "rgbd_odometry/app/run.hpp"

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <ostream>
#include <vector>

#include "rgbd_odometry/app/calibration.hpp"
#include "rgbd_odometry/app/odometry_sinks.hpp"
#include "rgbd_odometry/app/process_resources.hpp"
#include "rgbd_odometry/app/report.hpp"
#include "rgbd_odometry/core/clock.hpp"
#include "rgbd_odometry/app/config.hpp"
#include "rgbd_odometry/core/time_format.hpp"
#include "rgbd_odometry/app/config_file.hpp"
#include "rgbd_odometry/eval/evaluate.hpp"
#include "rgbd_odometry/io/imu_file.hpp"
#include "rgbd_odometry/io/odometry_log.hpp"
#include "rgbd_odometry/link/flight_link.hpp"
#include "rgbd_odometry/pipeline/pair_estimator.hpp"
#include "rgbd_odometry/pipeline/integrate.hpp"
#include "rgbd_odometry/runtime/realtime.hpp"
#include "rgbd_odometry/sensor/frame_feed.hpp"

namespace rgbdo {
namespace {

std::atomic<bool> g_stop{false};
std::atomic<bool> g_running{false};  // frames are being processed: a stop finishes them first
constexpr std::int64_t kLinkStatusPeriod_ns = 10'000'000'000;

// A step that cannot go on: the run ends with `code` (1 a failure, 2 a usage or configuration
// error) after printing "rgbd-odometry: " and the message.
struct RunExit {
  int code;
  std::string message;
};

// The configuration file, then the overrides in order, then --link; checked as a whole.
Config configure(const RunOptions& options) {
  Config config;
  if (!options.config_path.empty()) config = load_config(options.config_path);
  apply_overrides(config, options.overrides);
  if (!options.link.empty()) config.link.uri = options.link;
  validate(config);
  return config;
}

Config configure_or_exit(const RunOptions& options) {
  try {
    return configure(options);
  } catch (const ConfigError& e) {
    throw RunExit{2, std::string("configuration error: ") + e.what()};
  }
}

std::unique_ptr<FrameFeed> open_feed_or_exit(const RunOptions& options, const Config& config) {
  try {
    return open_frame_feed(options.source, config, config.sensor, options.max_frames);
  } catch (const SourceSpecError& e) {
    throw RunExit{2, e.what()};
  } catch (const SourceError& e) {
    throw RunExit{1, std::string("cannot open source: ") + e.what()};
  }
}

// Where the odometry goes besides the summary: the files asked for and the flight computer.
struct Destinations {
  std::unique_ptr<OdometryCsvWriter> log;
  std::unique_ptr<TrajectoryWriter> trajectory;
  std::unique_ptr<FlightLink> flight;
};

Destinations open_destinations_or_exit(const RunOptions& options, const Config& config, std::ostream& err) {
  Destinations d;
  try {
    // The log and the trajectory share the bound (each half of it).
    const auto bound = static_cast<std::uint64_t>(config.log.max_total_mb * 1e6 / 2);
    if (!options.log_path.empty()) d.log = std::make_unique<OdometryCsvWriter>(options.log_path, bound);
    if (!options.trajectory_path.empty()) d.trajectory = std::make_unique<TrajectoryWriter>(options.trajectory_path, bound);
  } catch (const std::exception& e) {
    throw RunExit{1, e.what()};
  }
  if (!config.link.uri.empty()) {
    try {
      d.flight = std::make_unique<FlightLink>(config.link, config.body);
      err << "rgbd-odometry: " << d.flight->startup_report() << "\n";
    } catch (const LinkError& e) {
      throw RunExit{1, std::string("cannot open the flight-computer link: ") + e.what()};
    }
  }
  return d;
}

// The gyro the frames' capture latency is measured against: a replay's file (--imu, or the
// recording's imu.txt), else, live, the followed autopilot's; null: none.
GyroFeed* choose_gyro_or_exit(const RunOptions& options, const FrameFeed& feed, FlightLink* flight,
                              std::unique_ptr<ImuFile>& imu_file) {
  try {
    std::string imu_path = options.imu_path;
    const std::string recording = feed.recording_directory();
    if (imu_path.empty() && !recording.empty() && std::filesystem::exists(recording + "/imu.txt"))
      imu_path = recording + "/imu.txt";
    if (!imu_path.empty()) {
      imu_file = std::make_unique<ImuFile>(imu_path);
      return imu_file.get();
    }
  } catch (const SourceError& e) {
    throw RunExit{1, e.what()};
  }
  return flight && feed.live() ? &flight->gyro() : nullptr;
}

// Where the integrated trajectory starts: the identity, or the ground truth at the first frame.
Eigen::Isometry3d start_pose_or_exit(const RunOptions& options, const FrameFeed& feed, const GroundTruth& groundtruth) {
  if (!options.start_at_groundtruth) return Eigen::Isometry3d::Identity();
  const auto first = feed.first_frame_stamp_ns();
  if (!first) return Eigen::Isometry3d::Identity();
  const auto gt = groundtruth.at(*first);
  if (!gt) throw RunExit{1, "--start-at-groundtruth: no ground truth at the first frame"};
  return *gt;
}

// --calibrate's needs, found out now, not after the run it would take to measure.
void check_calibration_or_exit(const RunOptions& options, const FrameFeed& feed, const GroundTruth& groundtruth) {
  if (options.calibration_path.empty()) return;
  if (groundtruth.empty())
    throw RunExit{2, "--calibrate needs a recording with ground truth (a TUM directory with groundtruth.txt); " +
                         feed.description() + " has none"};
  if (!std::ofstream(options.calibration_path, std::ios::app))
    throw RunExit{1, "cannot write the calibration to " + options.calibration_path};
}

// What happens to each frame the pipeline puts out: the sinks in order, the trajectory, the
// tallies for the summary. Runs on the pipeline's output thread, one frame at a time, in capture
// order; an output that throws stops the run (error() says why once it has stopped).
class FrameOutputs {
 public:
  FrameOutputs(const RunOptions& options, Destinations& to, AccuracyEvaluator& evaluator,
               const Eigen::Isometry3d& origin, std::ostream& out, std::ostream& err)
      : integrator_(origin), err_(err) {
    if (to.log) sinks_.push_back(std::make_unique<LogSink>(*to.log));
    if (to.flight) sinks_.push_back(std::make_unique<FlightLinkSink>(*to.flight));
    if (to.trajectory) sinks_.push_back(std::make_unique<TrajectorySink>(*to.trajectory));
    sinks_.push_back(std::make_unique<EvaluationSink>(evaluator, origin));
    if (!options.quiet) sinks_.push_back(std::make_unique<ConsoleSink>(out, options.verbose));
  }

  void operator()(const PairOutput& item) {
    if (!error_.empty()) return;
    resources_.frame();
    try {
      take(item);
    } catch (const std::exception& e) {
      error_ = e.what();  // reported once the run has stopped
      g_stop = true;
    }
  }

  const std::string& error() const { return error_; }
  const PairTallies& tallies() const { return tallies_; }
  const CaptureTiming& timing() const { return timing_; }
  const ResourceSampler& resources() const { return resources_; }

 private:
  void take(const PairOutput& item) {
    if (!item.frame_problem.empty())
      err_ << "rgbd-odometry: frame at " << format_seconds(item.t_frame_host_ns()) << ": " << item.frame_problem << "\n";
    if (!item.has_pair) {
      for (const auto& sink : sinks_) sink->frame(item, integrator_.pose());
      return;
    }
    const PairResult& r = item.result;
    if (PairEstimator::dropped_frame(r)) {
      // Logged and said, nothing else: no pose, no message, no evaluation; the next pair carries
      // whatever motion there was.
      for (const auto& sink : sinks_) sink->dropped(item);
      err_ << "rgbd-odometry: frame at " << format_seconds(item.t_frame_host_ns()) << " dropped: "
           << (r.status == Status::StampNotIncreasing ? "its capture time is not after the previous frame's"
                                                      : "no depth; the next frame pairs with the one before it")
           << "\n";
      return;
    }
    if (r.status == Status::Ok) integrator_.add(r.T_prev_curr);
    tallies_.add(r);
    timing_ = r.timing;
    for (const auto& sink : sinks_) sink->pair(item, pair_count_, integrator_.pose());
    ++pair_count_;
  }

  std::vector<std::unique_ptr<OdometrySink>> sinks_;
  TrajectoryIntegrator integrator_;
  std::ostream& err_;
  PairTallies tallies_;
  CaptureTiming timing_;  // as of the last pair
  ResourceSampler resources_;
  size_t pair_count_ = 0;
  std::string error_;
};

// The pipeline over the feed until it ends or a stop; with a flight link, the link's own status
// line beside the runtime's (every 10 s) and its news at once: an autopilot appearing or going
// is told within one tick of being noticed.
RealtimeStats run_pipeline_or_exit(const Config& config, FrameFeed& feed, FrameOutputs& outputs, FlightLink* flight,
                                   GyroFeed* gyro, std::ostream& err) {
  const auto on_message = [&err](const std::string& text) { err << "rgbd-odometry: " << text << "\n" << std::flush; };
  g_stop = false;
  try {
    RealtimePipeline pipeline(config, config.runtime, feed, [&outputs](const PairOutput& item) { outputs(item); },
                              on_message, gyro);
    if (flight) {
      std::int64_t next_link_status_ns = steady_now_ns() + kLinkStatusPeriod_ns;
      pipeline.set_tick([&, flight, next_link_status_ns]() mutable {
        const std::int64_t now_ns = steady_now_ns();
        flight->tick(now_ns);
        for (std::string news = flight->news(); !news.empty(); news = flight->news()) on_message("link: " + news);
        if (now_ns >= next_link_status_ns) {
          next_link_status_ns += kLinkStatusPeriod_ns;
          on_message("link status: " + flight->status_line());
        }
      });
    }
    g_running = true;  // stays so: a signal while the summary is written asks for no more than a stop
    return pipeline.run(g_stop);
  } catch (const ConfigError& e) {
    throw RunExit{2, std::string("configuration error: ") + e.what()};
  } catch (const std::exception& e) {
    throw RunExit{1, e.what()};
  }
}

void write_calibration_or_exit(const std::string& path, const Config& config, const AccuracySummary& summary,
                               const PairTallies& tallies, std::ostream& out) {
  const Calibration calibration = calibrate(config, summary, tallies.sensor);
  std::ofstream file(path);
  file << calibration_yaml(calibration);
  file.close();
  if (!file) throw RunExit{1, "cannot write the calibration to " + path};
  out << "  calibration written to " << path << ":\n" << calibration.notes;
}

void print_link_summary(const FlightLink& flight, std::ostream& out) {
  const LinkStats st = flight.stats();
  out << "  link: " << st.frames_sent << " MAVLink frames sent, " << st.frames_dropped_queue_full + st.frames_dropped_link_down
      << " dropped (" << st.frames_dropped_link_down << " while the link was down), " << st.reconnects
      << " reconnects\n";
  out << "  link status: " << flight.status_line() << "\n";
}

// The whole run; every early end is a RunExit.
int run_or_exit(const RunOptions& options, std::ostream& out, std::ostream& err) {
  const Config config = configure_or_exit(options);
  const std::unique_ptr<FrameFeed> feed = open_feed_or_exit(options, config);
  if (feed->live()) err << "rgbd-odometry: reading " << feed->description() << "\n";
  static const GroundTruth kNoGroundTruth;
  const GroundTruth& groundtruth = feed->groundtruth() ? *feed->groundtruth() : kNoGroundTruth;
  Destinations to = open_destinations_or_exit(options, config, err);

  std::unique_ptr<ImuFile> imu_file;
  GyroFeed* gyro = choose_gyro_or_exit(options, *feed, to.flight.get(), imu_file);
  if (gyro && config.latency.enabled)
    err << "rgbd-odometry: capture latency measured against the gyro of " << gyro->description() << "\n";
  const Eigen::Isometry3d origin = start_pose_or_exit(options, *feed, groundtruth);
  check_calibration_or_exit(options, *feed, groundtruth);
  GroundTruthAllowance allowance;
  try {
    allowance = parse_allowance(options.groundtruth_allowance, groundtruth);
  } catch (const std::invalid_argument& e) {
    throw RunExit{2, std::string("--groundtruth-allowance: ") + e.what()};
  }
  AccuracyEvaluator evaluator(groundtruth, allowance);

  FrameOutputs outputs(options, to, evaluator, origin, out, err);
  // A calibration reads the latencies from the frame pairs' own motions: the keyframes' pull on
  // each pair is a low-pass of earlier frames and would move them (bundled fr1_xyz frames: the
  // colour's 13.6 ms read as 18.7). The file written keeps the configuration as given.
  Config run_config = config;
  if (!options.calibration_path.empty()) run_config.keyframes.enabled = false;
  const RealtimeStats run = run_pipeline_or_exit(run_config, *feed, outputs, to.flight.get(), gyro, err);
  if (!outputs.error().empty()) throw RunExit{1, outputs.error()};
  if (!options.evaluation_path.empty() && evaluator.has_groundtruth()) {
    try {
      evaluator.write_csv(options.evaluation_path);
    } catch (const std::exception& e) {
      throw RunExit{1, e.what()};
    }
  }
  print_summary(out, evaluator.summary(), evaluator.has_groundtruth(), outputs.tallies(), run);
  print_capture_timing(out, outputs.timing(), config, run, feed->live());
  if (!options.calibration_path.empty())
    write_calibration_or_exit(options.calibration_path, config, evaluator.summary(), outputs.tallies(), out);
  if (const std::string sampled = outputs.resources().summary(); !sampled.empty())
    out << "  resources, memory the least over " << ResourceSampler::kWindowFrames << " frames: " << sampled << "\n";
  if (to.flight) print_link_summary(*to.flight, out);
  // The log and the summary above hold everything finished before a failure.
  if (!run.failure.empty()) throw RunExit{1, "stopped by a failure in the " + run.failure};
  return 0;
}

}  // namespace

int run_odometry(const RunOptions& options, std::ostream& out, std::ostream& err) {
  try {
    return run_or_exit(options, out, err);
  } catch (const RunExit& e) {
    err << "rgbd-odometry: " << e.message << "\n";
    return e.code;
  }
}

int print_configuration(const RunOptions& options, std::ostream& out, std::ostream& err) {
  try {
    out << config_yaml(configure(options));
    return 0;
  } catch (const ConfigError& e) {
    err << "rgbd-odometry: configuration error: " << e.what() << "\n";
    return 2;
  }
}

void request_stop() { g_stop = true; }

void on_stop_signal(int signal_number) {
  // Before the run (reading the configuration, opening the source) nothing is in hand to
  // finish, and a vendor parser or driver may not return: end at once, as without a handler.
  if (!g_running) std::_Exit(128 + signal_number);
  g_stop = true;
}

}  // namespace rgbdo
