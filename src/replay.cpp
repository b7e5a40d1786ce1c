#include "rgbd_odometry/replay.hpp"

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
#include "rgbd_odometry/tum_sequence.hpp"

namespace rgbdo {
namespace {

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

  const std::string scheme = "tum:";
  if (options.source.rfind(scheme, 0) != 0) {
    err << "rgbd-odometry: unsupported source '" << options.source
        << "': expected tum:DIR (a TUM RGB-D sequence directory)\n";
    return 2;
  }
  TumSequence sequence;
  try {
    sequence = open_tum_sequence(options.source.substr(scheme.size()));
  } catch (const SourceError& e) {
    err << "rgbd-odometry: cannot open source: " << e.what() << "\n";
    return 1;
  }

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
  if (options.start_at_groundtruth && !sequence.frames.empty()) {
    const auto gt = sequence.groundtruth.at(sequence.frames.front().t_colour_ns);
    if (!gt) {
      err << "rgbd-odometry: --start-at-groundtruth: no ground truth at the first frame\n";
      return 1;
    }
    origin = *gt;
  }

  OdometryPipeline pipeline(config);
  TrajectoryIntegrator integrator(origin);
  AccuracyEvaluator evaluator(sequence.groundtruth, config.covariance.scale);
  StageTimes total;
  int timed_pairs = 0;
  size_t frames = sequence.frames.size();
  if (options.max_frames > 0) frames = std::min(frames, static_cast<size_t>(options.max_frames));
  try {
    for (size_t i = 0; i < frames; ++i) {
      const RgbdFrame frame = load_tum_frame(sequence.frames[i], config.depth.units_per_m, config.camera.width,
                                             config.camera.height);
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

}  // namespace rgbdo
