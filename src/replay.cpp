#include "rgbd_odometry/replay.hpp"

#include <atomic>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <memory>
#include <ostream>
#include <sstream>

#include "rgbd_odometry/config.hpp"
#include "rgbd_odometry/evaluate.hpp"
#include "rgbd_odometry/integrate.hpp"
#include "rgbd_odometry/odometry.hpp"
#include "rgbd_odometry/odometry_log.hpp"
#include "rgbd_odometry/flight_link.hpp"
#include "rgbd_odometry/frame_feed.hpp"
#include "rgbd_odometry/realtime.hpp"
#include "rgbd_odometry/sensor_openni.hpp"
#include "rgbd_odometry/tum_sequence.hpp"
#include "rgbd_odometry/usb_devices.hpp"

namespace rgbdo {
namespace {

std::atomic<bool> g_stop{false};

constexpr double kRadToDeg = 180.0 / M_PI;

std::string pair_line(const PairResult& r, size_t index, bool verbose) {
  std::ostringstream s;
  s << std::fixed << "pair " << std::setw(4) << index << "  " << format_seconds(r.t_curr_ns) << "  "
    << std::left << std::setw(16) << status_word(r.status) << std::right;
  if (r.status == Status::Ok) {
    const Vector6d xi = xi_from_transform(r.T_prev_curr);
    const Vector6d sd = r.covariance.diagonal().cwiseSqrt();
    s << "inliers " << std::setw(4) << r.inliers << "/" << std::setw(4) << r.point_pairs << std::setprecision(2)
      << "  t[mm] " << std::showpos << std::setw(7) << xi(0) * 1e3 << std::setw(7) << xi(1) * 1e3 << std::setw(7)
      << xi(2) * 1e3 << "  r[deg] " << std::setw(6) << xi(3) * kRadToDeg << std::setw(6) << xi(4) * kRadToDeg
      << std::setw(6) << xi(5) * kRadToDeg << std::noshowpos << "  sd_t[mm] " << sd(0) * 1e3 << " " << sd(1) * 1e3
      << " " << sd(2) * 1e3 << "  sd_r[deg] " << std::setprecision(3) << sd(3) * kRadToDeg << " "
      << sd(4) * kRadToDeg << " " << sd(5) * kRadToDeg;
  } else {
    s << "features " << r.features_prev << "/" << r.features_curr << "  matches " << r.matches << "  with depth "
      << r.point_pairs;
  }
  if (verbose) {
    s << std::setprecision(2) << "  | features " << r.features_curr << " matches " << r.matches << " thr "
      << r.inlier_threshold_m * 1e3 << "mm | ms detect " << r.times.detect_ms << " match " << r.times.match_ms
      << " backproject " << r.times.backproject_ms << " ransac " << r.times.ransac_ms << " covariance "
      << r.times.covariance_ms;
  }
  return s.str();
}

void print_stats(std::ostream& out, const char* name, const ErrorStats& s, double factor, const char* unit) {
  out << "  " << std::left << std::setw(38) << name << std::right << std::fixed << std::setprecision(3) << "RMSE "
      << s.rmse * factor << "  median " << s.median * factor << "  max " << s.max * factor << " " << unit << "  ("
      << s.count << ")\n";
}

void print_summary(std::ostream& out, const AccuracySummary& s, bool with_groundtruth, const StageTimes& total,
                   int timed_pairs, const RealtimeStats& run) {
  out << "summary: " << s.pairs << " pairs, " << s.pairs - s.failed << " ok, " << s.failed << " failed";
  for (const auto& [word, n] : s.failures) out << " (" << word << ": " << n << ")";
  out << "\n";
  out << "  frames: " << run.frames << " processed, " << run.skipped << " skipped (processing behind), "
      << run.dropped_by_sensor << " dropped by the sensor; sensor lost " << run.sensor_losses << " times, re-opened "
      << run.reopens << " times\n";
  if (run.latency.count() > 0)
    out << std::fixed << std::setprecision(2) << "  latency capture to output: median " << run.latency.quantile_ms(0.5)
        << " ms, p99 " << run.latency.quantile_ms(0.99) << " ms, max " << run.latency.max_ms() << " ms ("
        << run.latency.count() << " pairs)\n";
  if (run.latency.ahead_of_clock() > 0)
    out << "  latency capture to output: not measurable for " << run.latency.ahead_of_clock()
        << " pairs, whose capture time is ahead of the host clock (the device clock runs at another rate;"
           " the virtual sensor at rate != 1 keeps the recording's times)\n";
  if (timed_pairs > 0) {
    const double n = timed_pairs;
    const double frame_ms = (total.detect_ms + total.match_ms + total.backproject_ms + total.ransac_ms +
                             total.covariance_ms) / n;
    out << std::fixed << std::setprecision(2) << "  time per frame (decode excluded): " << frame_ms << " ms = "
        << 1000.0 / frame_ms << " frames/s  [detect " << total.detect_ms / n << ", match " << total.match_ms / n
        << ", backproject " << total.backproject_ms / n << ", ransac " << total.ransac_ms / n << ", covariance "
        << total.covariance_ms / n << " ms]\n";
  }
  if (!with_groundtruth) {
    out << "  no groundtruth.txt: accuracy not evaluated\n";
    return;
  }
  out << "  accuracy against ground truth (" << s.evaluated << " pairs):\n";
  print_stats(out, "frame-to-frame RPE, translation", s.rpe_translation_m, 1e3, "mm");
  print_stats(out, "frame-to-frame RPE, rotation", s.rpe_rotation_deg, 1.0, "deg");
  print_stats(out, "drift over 1 s windows, translation", s.drift_translation_mps, 1.0, "m/s");
  print_stats(out, "drift over 1 s windows, rotation", s.drift_rotation_degps, 1.0, "deg/s");
  out << std::setprecision(2) << "  covariance, per axis: mean e^2/var " << s.mean_axis_nees
      << " (1 when consistent) [t " << s.axis_nees(0) << " " << s.axis_nees(1) << " " << s.axis_nees(2) << ", r "
      << s.axis_nees(3) << " " << s.axis_nees(4) << " " << s.axis_nees(5) << "]; 1 at covariance.scale "
      << s.consistent_scale << "\n";
  out << "  covariance, joint 6-D: mean NEES " << s.mean_nees << " (6 when consistent), median " << s.median_nees
      << " (5.35), " << std::setprecision(1) << 100.0 * s.nees_within_95 << "% within the 95% bound\n";
}

}  // namespace

int run_odometry(const RunOptions& options, std::ostream& out, std::ostream& err) {
  Config config;
  try {
    if (!options.config_path.empty()) config = load_config(options.config_path);
    apply_overrides(config, options.overrides);
    if (!options.link.empty()) config.link.uri = options.link;
    validate(config);
  } catch (const ConfigError& e) {
    err << "rgbd-odometry: configuration error: " << e.what() << "\n";
    return 2;
  }

  const std::string tum_scheme = "tum:", openni_scheme = "openni://", oni_scheme = "oni:";
  std::unique_ptr<FrameFeed> feed;
  try {
    if (options.source.rfind(tum_scheme, 0) == 0) {
      feed = std::make_unique<TumFeed>(open_tum_sequence(options.source.substr(tum_scheme.size())), config,
                                       options.max_frames);
    } else if (options.source.rfind(openni_scheme, 0) == 0 || options.source.rfind(oni_scheme, 0) == 0) {
      const bool file = options.source.rfind(oni_scheme, 0) == 0;
      OpenNiOptions o;
      o.uri = options.source.substr(file ? oni_scheme.size() : openni_scheme.size());
      if (file && (o.uri.size() < 5 || o.uri.compare(o.uri.size() - 4, 4, ".oni") != 0)) {
        err << "rgbd-odometry: oni:FILE needs a file ending in .oni, got '" << o.uri << "'\n";
        return 2;
      }
      o.width = config.camera.width;
      o.height = config.camera.height;
      o.fps = config.sensor.fps;
      o.registration = config.sensor.registration;
      o.frame_timeout_ms = config.sensor.frame_timeout_ms;
      o.pairing_wait_ms = config.sensor.pairing_wait_ms;
      o.record_path = config.sensor.record_oni;
      feed = std::make_unique<OpenNiFeed>(o, options.max_frames);
    } else {
      err << "rgbd-odometry: unsupported source '" << options.source
          << "': expected tum:DIR (a TUM RGB-D sequence directory), openni://[DEVICE-URI] or oni:FILE.oni\n";
      return 2;
    }
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
    if (!options.log_path.empty()) log = std::make_unique<OdometryCsvWriter>(options.log_path);
    if (!options.trajectory_path.empty()) trajectory = std::make_unique<TrajectoryWriter>(options.trajectory_path);
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

  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();
  const auto* tum = dynamic_cast<const TumFeed*>(feed.get());
  if (options.start_at_groundtruth && tum && !tum->sequence().frames.empty()) {
    const auto gt = groundtruth.at(tum->sequence().frames.front().t_colour_ns);
    if (!gt) {
      err << "rgbd-odometry: --start-at-groundtruth: no ground truth at the first frame\n";
      return 1;
    }
    origin = *gt;
  }

  TrajectoryIntegrator integrator(origin);
  AccuracyEvaluator evaluator(groundtruth, config.covariance.scale);
  StageTimes total;
  int timed_pairs = 0;
  size_t pair_count = 0;
  std::string output_error;
  // Runs on the pipeline's output thread, one frame at a time, in capture order.
  const auto on_output = [&](const PairOutput& item) {
    if (!output_error.empty()) return;
    try {
      if (!item.frame_problem.empty()) err << "rgbd-odometry: frame at " << format_seconds(item.t_frame_ns) << ": " << item.frame_problem << "\n";
      if (!item.has_pair) {
        if (trajectory) trajectory->write(item.t_frame_ns, integrator.pose());
        return;
      }
      const PairResult& r = item.result;
      if (r.status == Status::Ok) {
        integrator.add(r.T_prev_curr);
        total.detect_ms += r.times.detect_ms;
        total.match_ms += r.times.match_ms;
        total.backproject_ms += r.times.backproject_ms;
        total.ransac_ms += r.times.ransac_ms;
        total.covariance_ms += r.times.covariance_ms;
        ++timed_pairs;
      }
      if (log) log->write(r);
      if (flight) flight->send_pair(r);
      if (trajectory) trajectory->write(item.t_frame_ns, integrator.pose());
      evaluator.add(r, origin.inverse() * integrator.pose());
      ++pair_count;
      if (!options.quiet) {
        out << pair_line(r, pair_count - 1, options.verbose);
        if (item.skipped > 0) out << "  (" << item.skipped << " frames skipped)";
        if (options.verbose) out << std::fixed << std::setprecision(1) << " | latency " << item.latency_ms << " ms";
        out << "\n";
      }
    } catch (const std::exception& e) {
      output_error = e.what();  // reported once the run has stopped
      g_stop = true;
    }
  };
  const auto on_message = [&](const std::string& text) { err << "rgbd-odometry: " << text << "\n" << std::flush; };

  g_stop = false;
  RealtimeStats run;
  try {
    RealtimePipeline pipeline(config, *feed, on_output, on_message);
    if (flight) {
      pipeline.set_tick([&] {
        flight->tick(std::chrono::duration_cast<std::chrono::nanoseconds>(
                         std::chrono::steady_clock::now().time_since_epoch())
                         .count());
        if (const std::string news = flight->news(); !news.empty()) on_message("link: " + news);
      });
    }
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
  print_summary(out, evaluator.summary(), evaluator.has_groundtruth(), total, timed_pairs, run);
  if (flight) {
    const LinkStats st = flight->stats();
    out << "  link: " << st.frames_sent << " MAVLink frames sent, " << st.frames_dropped_queue_full + st.frames_dropped_link_down
        << " dropped (" << st.frames_dropped_link_down << " while the link was down), " << st.reconnects
        << " reconnects\n";
  }
  return 0;
}

void request_stop() { g_stop = true; }

int list_devices(std::ostream& out, int width, int height, int fps) {
  // OpenNI2's view: the devices it can open (the real runtime, with every installed driver).
  std::vector<DeviceDescription> devices;
  int rc = 0;
  try {
    devices = list_openni_devices();
  } catch (const SourceError& e) {
    out << "cannot list OpenNI2 devices: " << e.what() << "\n";
    rc = 1;
  }
  // USB's view: where each sensor is plugged in and how fast (a sensor OpenNI2 does not
  // list, driver missing or no permission, still shows here).
  std::vector<UsbDevice> usb;
  std::string usb_problem;
  try {
    usb = list_usb_devices();
  } catch (const std::exception& e) {
    usb_problem = e.what();
  }
  std::vector<const UsbDevice*> sensors;
  for (const auto& u : usb)
    if (!u.known_as.empty()) sensors.push_back(&u);

  if (devices.empty()) out << "no OpenNI2 device found (is the sensor plugged in, and is its USB port powered?)\n";
  for (const auto& d : devices) {
    char ids[32];
    std::snprintf(ids, sizeof ids, "%04x:%04x", d.usb_vendor_id, d.usb_product_id);
    out << "OpenNI2: " << d.uri << "  " << d.vendor << " " << d.name << "  usb " << ids << "\n";
  }
  if (!usb_problem.empty()) {
    out << "USB: cannot look at the USB devices: " << usb_problem << "\n";
  } else if (sensors.empty()) {
    out << "USB: no RGB-D sensor on USB (" << usb.size() << " other USB devices)\n";
  }
  for (const UsbDevice* u : sensors) {
    char ids[32];
    std::snprintf(ids, sizeof ids, "%04x:%04x", u->vendor_id, u->product_id);
    out << "USB: " << u->known_as << "  " << ids << "  bus " << u->bus << " port " << u->port_path << " address "
        << u->address << "  " << u->speed_name << "\n";
    const UsbBandwidth b = check_usb_bandwidth(u->speed_mbps, width, height, fps);
    if (!b.sufficient) out << "  WARNING: " << b.message << "\n";
  }
  return rc;
}

}  // namespace rgbdo
