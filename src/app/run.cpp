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
#include "rgbd_odometry/core/config.hpp"
#include "rgbd_odometry/core/time_format.hpp"
#include "rgbd_odometry/io/config_file.hpp"
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

// The configuration file, then the overrides in order, then --link; checked as a whole.
Config configure(const RunOptions& options) {
  Config config;
  if (!options.config_path.empty()) config = load_config(options.config_path);
  apply_overrides(config, options.overrides);
  if (!options.link.empty()) config.link.uri = options.link;
  validate(config);
  if (!config.link.uri.empty()) {
    try {
      (void)parse_link_uri(config.link.uri);
    } catch (const LinkError& e) {
      throw ConfigError(std::string("config key 'link.uri': ") + e.what());
    }
  }
  return config;
}

}  // namespace

int run_odometry(const RunOptions& options, std::ostream& out, std::ostream& err) {
  Config config;
  try {
    config = configure(options);
  } catch (const ConfigError& e) {
    err << "rgbd-odometry: configuration error: " << e.what() << "\n";
    return 2;
  }

  std::unique_ptr<FrameFeed> feed;
  try {
    feed = open_frame_feed(options.source, config, options.max_frames);
  } catch (const SourceSpecError& e) {
    err << "rgbd-odometry: " << e.what() << "\n";
    return 2;
  } catch (const SourceError& e) {
    err << "rgbd-odometry: cannot open source: " << e.what() << "\n";
    return 1;
  }
  if (feed->live()) err << "rgbd-odometry: reading " << feed->description() << "\n";
  static const GroundTruth kNoGroundTruth;
  const GroundTruth& groundtruth = feed->groundtruth() ? *feed->groundtruth() : kNoGroundTruth;

  std::unique_ptr<OdometryCsvWriter> log;
  std::unique_ptr<TrajectoryWriter> trajectory;
  try {
    // The log and the trajectory share the bound (each half of it).
    const auto bound = static_cast<std::uint64_t>(config.log.max_total_mb * 1e6 / 2);
    if (!options.log_path.empty()) log = std::make_unique<OdometryCsvWriter>(options.log_path, bound);
    if (!options.trajectory_path.empty()) trajectory = std::make_unique<TrajectoryWriter>(options.trajectory_path, bound);
  } catch (const std::exception& e) {
    err << "rgbd-odometry: " << e.what() << "\n";
    return 1;
  }

  std::unique_ptr<FlightLink> flight;
  if (!config.link.uri.empty()) {
    try {
      flight = std::make_unique<FlightLink>(config);
      err << "rgbd-odometry: " << flight->startup_report() << "\n";
    } catch (const LinkError& e) {
      err << "rgbd-odometry: cannot open the flight-computer link: " << e.what() << "\n";
      return 1;
    }
  }

  const auto* tum = dynamic_cast<const TumFeed*>(feed.get());
  // The gyro the frames' capture latency is measured against: a replay's file (--imu, or the
  // recording's imu.txt), else, live, the followed autopilot's.
  std::unique_ptr<ImuFile> imu_file;
  GyroFeed* gyro = nullptr;
  try {
    std::string imu_path = options.imu_path;
    if (imu_path.empty() && tum && std::filesystem::exists(tum->sequence().directory + "/imu.txt"))
      imu_path = tum->sequence().directory + "/imu.txt";
    if (!imu_path.empty()) {
      imu_file = std::make_unique<ImuFile>(imu_path);
      gyro = imu_file.get();
    }
  } catch (const SourceError& e) {
    err << "rgbd-odometry: " << e.what() << "\n";
    return 1;
  }
  if (!gyro && flight && feed->live()) gyro = &flight->gyro();
  if (gyro && config.latency.enabled)
    err << "rgbd-odometry: capture latency measured against the gyro of " << gyro->description() << "\n";

  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();
  if (options.start_at_groundtruth && tum && !tum->sequence().frames.empty()) {
    const auto gt = groundtruth.at(tum->sequence().frames.front().t_colour_ns);
    if (!gt) {
      err << "rgbd-odometry: --start-at-groundtruth: no ground truth at the first frame\n";
      return 1;
    }
    origin = *gt;
  }

  if (!options.calibration_path.empty() && groundtruth.empty()) {
    err << "rgbd-odometry: --calibrate needs a recording with ground truth (a TUM directory with "
           "groundtruth.txt); " << feed->description() << " has none\n";
    return 2;
  }
  if (!options.calibration_path.empty() && !std::ofstream(options.calibration_path, std::ios::app)) {
    // Found out now, not after the run it would take to measure.
    err << "rgbd-odometry: cannot write the calibration to " << options.calibration_path << "\n";
    return 1;
  }

  TrajectoryIntegrator integrator(origin);
  GroundTruthAllowance allowance;
  try {
    allowance = parse_allowance(options.groundtruth_allowance, groundtruth);
  } catch (const std::invalid_argument& e) {
    err << "rgbd-odometry: --groundtruth-allowance: " << e.what() << "\n";
    return 2;
  }
  AccuracyEvaluator evaluator(groundtruth, allowance);
  // The outputs, in the order each frame reaches them.
  std::vector<std::unique_ptr<OdometrySink>> sinks;
  if (log) sinks.push_back(std::make_unique<LogSink>(*log));
  if (flight) sinks.push_back(std::make_unique<FlightLinkSink>(*flight));
  if (trajectory) sinks.push_back(std::make_unique<TrajectorySink>(*trajectory));
  sinks.push_back(std::make_unique<EvaluationSink>(evaluator, origin));
  if (!options.quiet) sinks.push_back(std::make_unique<ConsoleSink>(out, options.verbose));
  PairTallies tallies;
  CaptureTiming timing;  // as of the last pair
  ResourceSampler resources;
  size_t pair_count = 0;
  std::string output_error;
  // Runs on the pipeline's output thread, one frame at a time, in capture order.
  const auto on_output = [&](const PairOutput& item) {
    if (!output_error.empty()) return;
    resources.frame();
    try {
      if (!item.frame_problem.empty())
        err << "rgbd-odometry: frame at " << format_seconds(item.t_frame_host_ns()) << ": "
            << item.frame_problem << "\n";
      if (!item.has_pair) {
        for (const auto& sink : sinks) sink->frame(item, integrator.pose());
        return;
      }
      const PairResult& r = item.result;
      if (PairEstimator::dropped_frame(r)) {
        // Logged and said, nothing else: no pose, no message, no evaluation over no time.
        for (const auto& sink : sinks) sink->dropped(item);
        err << "rgbd-odometry: frame at " << format_seconds(item.t_frame_host_ns())
            << " dropped: its capture time is not after the previous frame's\n";
        return;
      }
      if (r.status == Status::Ok) integrator.add(r.T_prev_curr);
      tallies.add(r);
      timing = r.timing;
      for (const auto& sink : sinks) sink->pair(item, pair_count, integrator.pose());
      ++pair_count;
    } catch (const std::exception& e) {
      output_error = e.what();  // reported once the run has stopped
      g_stop = true;
    }
  };
  const auto on_message = [&](const std::string& text) { err << "rgbd-odometry: " << text << "\n" << std::flush; };

  g_stop = false;
  RealtimeStats run;
  try {
    RealtimePipeline pipeline(config, *feed, on_output, on_message, gyro);
    if (flight) {
      // The link's own status line beside the runtime's (every 10 s), and its news at once:
      // an autopilot appearing or going is told within one tick of being noticed.
      std::int64_t next_link_status_ns = steady_now_ns() + kLinkStatusPeriod_ns;
      pipeline.set_tick([&, next_link_status_ns]() mutable {
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
    run = pipeline.run(g_stop);
  } catch (const ConfigError& e) {
    err << "rgbd-odometry: configuration error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    err << "rgbd-odometry: " << e.what() << "\n";
    return 1;
  }
  if (!output_error.empty()) {
    err << "rgbd-odometry: " << output_error << "\n";
    return 1;
  }
  if (!options.evaluation_path.empty() && evaluator.has_groundtruth()) {
    try {
      evaluator.write_csv(options.evaluation_path);
    } catch (const std::exception& e) {
      err << "rgbd-odometry: " << e.what() << "\n";
      return 1;
    }
  }
  print_summary(out, evaluator.summary(), evaluator.has_groundtruth(), tallies, run);
  print_capture_timing(out, timing, config, run, feed->live());
  if (!options.calibration_path.empty()) {
    const Calibration calibration = calibrate(config, evaluator.summary(), tallies.sensor);
    std::ofstream file(options.calibration_path);
    file << calibration_yaml(calibration);
    file.close();
    if (!file) {
      err << "rgbd-odometry: cannot write the calibration to " << options.calibration_path << "\n";
      return 1;
    }
    out << "  calibration written to " << options.calibration_path << ":\n" << calibration.notes;
  }
  if (const std::string sampled = resources.summary(); !sampled.empty()) out << "  resources, memory the least over " << ResourceSampler::kWindowFrames << " frames: " << sampled << "\n";
  if (flight) {
    const LinkStats st = flight->stats();
    out << "  link: " << st.frames_sent << " MAVLink frames sent, " << st.frames_dropped_queue_full + st.frames_dropped_link_down
        << " dropped (" << st.frames_dropped_link_down << " while the link was down), " << st.reconnects
        << " reconnects\n";
    out << "  link status: " << flight->status_line() << "\n";
  }
  if (!run.failure.empty()) {
    // The log and the summary above hold everything finished before the failure.
    err << "rgbd-odometry: stopped by a failure in the " << run.failure << "\n";
    return 1;
  }
  return 0;
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
