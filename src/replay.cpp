#include "rgbd_odometry/replay.hpp"

#include <atomic>
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
#include "rgbd_odometry/sensor_openni.hpp"
#include "rgbd_odometry/tum_sequence.hpp"

namespace rgbdo {
namespace {

std::atomic<bool> g_stop{false};

// Where frames come from: a recorded TUM sequence or a live OpenNI2 device.
class FrameFeed {
 public:
  virtual ~FrameFeed() = default;
  // False at the end (or when the device stopped delivering: `problem` says why).
  virtual bool next(RgbdFrame& frame, std::string& problem) = 0;
  virtual const GroundTruth* groundtruth() const { return nullptr; }
};

class TumFeed : public FrameFeed {
 public:
  TumFeed(TumSequence sequence, const Config& config, int max_frames)
      : seq_(std::move(sequence)), config_(config),
        end_(max_frames > 0 ? std::min(seq_.frames.size(), static_cast<size_t>(max_frames)) : seq_.frames.size()) {}
  bool next(RgbdFrame& frame, std::string&) override {
    if (i_ >= end_) return false;
    frame = load_tum_frame(seq_.frames[i_++], config_.depth.units_per_m, config_.camera.width, config_.camera.height);
    return true;
  }
  const GroundTruth* groundtruth() const override { return &seq_.groundtruth; }
  const TumSequence& sequence() const { return seq_; }

 private:
  TumSequence seq_;
  Config config_;
  size_t end_, i_ = 0;
};

class OpenNiFeed : public FrameFeed {
 public:
  explicit OpenNiFeed(const OpenNiOptions& options) : source_(options) {}
  bool next(RgbdFrame& frame, std::string& problem) override { return source_.next(frame, problem); }
  const OpenNiSource& source() const { return source_; }

 private:
  OpenNiSource source_;
};

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
                   int timed_pairs) {
  out << "summary: " << s.pairs << " pairs, " << s.pairs - s.failed << " ok, " << s.failed << " failed";
  for (const auto& [word, n] : s.failures) out << " (" << word << ": " << n << ")";
  out << "\n";
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
    validate(config);
  } catch (const ConfigError& e) {
    err << "rgbd-odometry: configuration error: " << e.what() << "\n";
    return 2;
  }

  const std::string tum_scheme = "tum:", openni_scheme = "openni://";
  std::unique_ptr<FrameFeed> feed;
  try {
    if (options.source.rfind(tum_scheme, 0) == 0) {
      feed = std::make_unique<TumFeed>(open_tum_sequence(options.source.substr(tum_scheme.size())), config,
                                       options.max_frames);
    } else if (options.source.rfind(openni_scheme, 0) == 0) {
      OpenNiOptions o;
      o.uri = options.source.substr(openni_scheme.size());
      o.width = config.camera.width;
      o.height = config.camera.height;
      auto live = std::make_unique<OpenNiFeed>(o);
      err << "rgbd-odometry: reading " << live->source().description() << "\n";
      feed = std::move(live);
    } else {
      err << "rgbd-odometry: unsupported source '" << options.source
          << "': expected tum:DIR (a TUM RGB-D sequence directory) or openni://[DEVICE-URI]\n";
      return 2;
    }
  } catch (const SourceError& e) {
    err << "rgbd-odometry: cannot open source: " << e.what() << "\n";
    return 1;
  }
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

  OdometryPipeline pipeline(config);
  TrajectoryIntegrator integrator(origin);
  AccuracyEvaluator evaluator(groundtruth, config.covariance.scale);
  StageTimes total;
  int timed_pairs = 0;
  g_stop = false;
  try {
    RgbdFrame frame;
    std::string problem;
    for (size_t i = 0; !g_stop; ++i) {
      if (!feed->next(frame, problem)) {
        if (!problem.empty()) err << "rgbd-odometry: source stopped: " << problem << "\n";
        break;
      }
      if (frame.status != Status::Ok) err << "rgbd-odometry: frame " << i << ": " << frame.problem << "\n";
      const auto result = pipeline.process(frame);
      if (!result) {
        if (trajectory) trajectory->write(frame.t_colour_ns, integrator.pose());
        continue;
      }
      if (result->status == Status::Ok) {
        integrator.add(result->T_prev_curr);
        total.detect_ms += result->times.detect_ms;
        total.match_ms += result->times.match_ms;
        total.backproject_ms += result->times.backproject_ms;
        total.ransac_ms += result->times.ransac_ms;
        total.covariance_ms += result->times.covariance_ms;
        ++timed_pairs;
      }
      if (log) log->write(*result);
      if (trajectory) trajectory->write(frame.t_colour_ns, integrator.pose());
      evaluator.add(*result, origin.inverse() * integrator.pose());
      if (!options.quiet) out << pair_line(*result, i - 1, options.verbose) << "\n";
    }
  } catch (const std::exception& e) {
    err << "rgbd-odometry: " << e.what() << "\n";
    return 1;
  }
  print_summary(out, evaluator.summary(), evaluator.has_groundtruth(), total, timed_pairs);
  return 0;
}

void request_stop() { g_stop = true; }

int list_devices(std::ostream& out) {
  try {
    const auto devices = list_openni_devices();
    if (devices.empty()) {
      out << "no OpenNI2 device found (is the sensor plugged in, and is its USB port powered?)\n";
      return 0;
    }
    for (const auto& d : devices) {
      char ids[32];
      std::snprintf(ids, sizeof ids, "%04x:%04x", d.usb_vendor_id, d.usb_product_id);
      out << d.uri << "  " << d.vendor << " " << d.name << "  usb " << ids << "\n";
    }
    return 0;
  } catch (const SourceError& e) {
    out << "cannot list OpenNI2 devices: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace rgbdo
