#include "rgbd_odometry/app/report.hpp"

#include <cmath>
#include <iomanip>
#include <ostream>
#include <sstream>

#include "rgbd_odometry/core/geometry.hpp"
#include "rgbd_odometry/core/time_format.hpp"

namespace rgbdo {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

// digits: a drift of centimetres a second needs four to show a change of a few percent.
void print_stats(std::ostream& out, const char* name, const ErrorStats& s, double factor, const char* unit,
                 int digits = 3) {
  out << "  " << std::left << std::setw(38) << name << std::right << std::fixed << std::setprecision(digits) << "RMSE "
      << s.rmse * factor << "  median " << s.median * factor << "  max " << s.max * factor << " " << unit << "  ("
      << s.count << ")\n";
}

void print_nees(std::ostream& out, const char* name, const NeesStats& n) {
  if (n.count == 0) {
    out << "    " << name << ": none evaluated\n";
    return;
  }
  out << std::fixed << std::setprecision(2) << "    " << name << " (" << n.count << "): mean " << n.mean
      << " (6 when consistent), median " << n.median << " (5.35), " << std::setprecision(1) << 100.0 * n.within_95
      << "% below the chi2(6) 95% gate\n";
}

// Which time offset against the ground truth the estimated motions' `part` matches best: a
// stream's capture-to-stamp latency (or the reference's own time alignment).
void print_time_offset(std::ostream& out, const char* part, const TimeOffsetFit& o, double factor, const char* unit) {
  if (o.pairs == 0) return;
  out << std::fixed << std::setprecision(1) << "  time offset against the ground truth, " << part << ": ";
  if (!o.found) {
    out << "no best offset within +-" << o.max_offset_s * 1e3 << " ms (" << o.pairs << " pairs)\n";
    return;
  }
  out << "best with the frames taken " << o.offset_s * 1e3 << " +- " << o.standard_error_s * 1e3
      << " ms before their stamps (" << o.pairs
      << " pairs; RMSE " << std::setprecision(3) << o.rmse_at_stamps * factor << " " << unit << " at the stamps, "
      << o.rmse_at_offset * factor << " at the offset)\n";
}

}  // namespace

std::string pair_line(const PairResult& r, std::size_t index, bool verbose) {
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
    s << std::setprecision(2) << "  | features " << r.features_curr << " matches " << r.matches << " tracked "
      << r.tracked << " thr "
      << r.inlier_threshold_m * 1e3 << "mm | ms detect " << r.times.detect_ms << " match " << r.times.match_ms
      << " backproject " << r.times.backproject_ms << " ransac " << r.times.ransac_ms << " covariance "
      << r.times.covariance_ms << " keyframe " << r.times.keyframe_ms << (r.rematched ? " | rematched" : "")
      << " | keyframe " << r.keyframe.id << (r.keyframe.created ? " new" : "") << (r.keyframe.returned ? " return" : "");
  }
  return s.str();
}

void PairTallies::add(const PairResult& r) {
  if (r.status == Status::Ok) {
    total.detect_ms += r.times.detect_ms;
    total.match_ms += r.times.match_ms;
    total.backproject_ms += r.times.backproject_ms;
    total.ransac_ms += r.times.ransac_ms;
    total.covariance_ms += r.times.covariance_ms;
    total.keyframe_ms += r.times.keyframe_ms;
    ++timed;
    keyframes_made += r.keyframe.created ? 1 : 0;
    keyframe_returns += r.keyframe.returned ? 1 : 0;
    keyframe_measured += r.keyframe.inliers > 0 ? 1 : 0;
    depth_refined += r.depth_points > 0 ? 1 : 0;
    depth_trusted += r.depth_points > 0 && r.depth_trusted ? 1 : 0;
    point_pairs += r.point_pairs;
    tracked += r.tracked;
    sensor = r.sensor;
  }
  rematched += r.rematched ? 1 : 0;
}

void print_summary(std::ostream& out, const AccuracySummary& s, bool with_groundtruth, const PairTallies& tallies,
                   const RealtimeStats& run) {
  const StageTimes& total = tallies.total;
  const int timed_pairs = tallies.timed;
  out << "summary: " << s.pairs << " pairs, " << s.pairs - s.failed << " ok, " << s.failed << " failed";
  for (const auto& [word, n] : s.failures) out << " (" << word << ": " << n << ")";
  out << "\n";
  out << "  frames: " << run.frames << " processed, " << run.skipped << " skipped (processing behind), "
      << run.without_depth << " without a depth frame within 20 ms, " << run.dropped_by_sensor
      << " dropped by the sensor, " << run.stamp_not_increasing
      << " dropped for a capture time not after the previous frame's, " << run.bridged_without_depth
      << " without depth bridged (the next frame paired with the one before); sensor lost " << run.sensor_losses
      << " times, re-opened " << run.reopens << " times\n";
  if (run.latency.count() > 0)
    out << std::fixed << std::setprecision(2) << "  latency capture to output: median " << run.latency.quantile_ms(0.5)
        << " ms, p99 " << run.latency.quantile_ms(0.99) << " ms, max " << run.latency.max_ms() << " ms ("
        << run.latency.count() << " pairs)\n";
  if (run.latency.ahead_of_clock() > 0)
    out << "  latency capture to output: not measurable for " << run.latency.ahead_of_clock()
        << " pairs, whose capture time is ahead of the host clock (a fault of the device clock's mapping:"
           " sensor/device_clock.hpp takes off every lead a frame proves)\n";
  if (timed_pairs > 0) {
    const double n = timed_pairs;
    const double frame_ms = (total.detect_ms + total.match_ms + total.backproject_ms + total.ransac_ms +
                             total.covariance_ms + total.keyframe_ms) / n;
    out << std::fixed << std::setprecision(2) << "  time per frame (decode excluded): " << frame_ms << " ms = "
        << 1000.0 / frame_ms << " frames/s  [detect " << total.detect_ms / n << ", match " << total.match_ms / n
        << ", backproject " << total.backproject_ms / n << ", ransac " << total.ransac_ms / n << ", covariance "
        << total.covariance_ms / n << ", keyframe " << total.keyframe_ms / n << " ms]\n";
  }
  if (tallies.keyframes_made > 0)
    out << "  keyframes: " << tallies.keyframes_made << " made, " << tallies.keyframe_returns
        << " returns to a kept one; " << tallies.keyframe_measured << " of " << timed_pairs
        << " good pairs measured against theirs\n";
  if (tallies.tracked > 0)
    out << std::setprecision(1) << "  sub-pixel tracking: " << tallies.tracked << " of " << tallies.point_pairs
        << " point pairs (" << 100.0 * static_cast<double>(tallies.tracked) / static_cast<double>(tallies.point_pairs)
        << " %); the others kept the detector's corner (no texture across the patch, a track too far or off the image)\n";
  if (tallies.rematched > 0)
    out << "  matching: " << tallies.rematched << " pairs matched again over the whole image (the motion window fell short)\n";
  const SensorEstimates& learnt = tallies.sensor;
  if (timed_pairs > 0 && learnt.depth_sigma_scale_t > 0) {
    out << std::setprecision(1) << "  depth alignment: fused into " << tallies.depth_refined << " of " << timed_pairs
        << " good pairs (" << tallies.depth_trusted << " at the factors learnt against the features, "
        << tallies.depth_refined - tallies.depth_trusted
        << " at the fixed refinement.distrusted_sigma_scale); its own sigma scaled by " << learnt.depth_sigma_scale_t
        << " (translation) and " << learnt.depth_sigma_scale_r << " (rotation), learnt\n";
    out << "  sensor, learnt from the data: " << sensor_estimates_text(learnt) << "\n";
  }
  if (!with_groundtruth) {
    out << "  no groundtruth.txt: accuracy not evaluated\n";
    return;
  }
  out << "  accuracy against ground truth (" << s.evaluated << " pairs):\n";
  print_stats(out, "frame-to-frame RPE, translation", s.rpe_translation_m, 1e3, "mm");
  print_stats(out, "frame-to-frame RPE, rotation", s.rpe_rotation_deg, 1.0, "deg");
  print_stats(out, "drift over 1 s windows, translation", s.drift_translation_mps, 1.0, "m/s", 4);
  print_stats(out, "drift over 1 s windows, rotation", s.drift_rotation_degps, 1.0, "deg/s");
  out << std::setprecision(2) << "  covariance, with the ground truth's noise allowed for (" << s.allowance.translation_m * 1e3
      << " mm, " << std::setprecision(3) << s.allowance.rotation_rad * kRadToDeg << " deg per axis; " << s.allowance.origin << "):\n";
  out << "    per axis: mean e^2/var (1 when consistent) [t " << s.axis_nees(0) << " " << s.axis_nees(1) << " "
      << s.axis_nees(2) << ", r " << s.axis_nees(3) << " " << s.axis_nees(4) << " " << s.axis_nees(5) << "]\n";
  out << std::setprecision(1) << "    per axis: % within 3 sigma [t " << 100 * s.axis_within_3sigma(0) << " "
      << 100 * s.axis_within_3sigma(1) << " " << 100 * s.axis_within_3sigma(2) << ", r " << 100 * s.axis_within_3sigma(3)
      << " " << 100 * s.axis_within_3sigma(4) << " " << 100 * s.axis_within_3sigma(5) << "]\n";
  print_nees(out, "joint 6-D NEES per pair", s.pair_nees);
  print_nees(out, "joint 6-D NEES over 1 s windows", s.window_nees);
  out << std::setprecision(2) << "    over 1 s windows, per axis: mean e^2/var [t " << s.window_axis_nees(0) << " "
      << s.window_axis_nees(1) << " " << s.window_axis_nees(2) << ", r " << s.window_axis_nees(3) << " "
      << s.window_axis_nees(4) << " " << s.window_axis_nees(5) << "]\n";
  out << std::setprecision(2) << "    lag-1 correlation of consecutive pairs' errors (" << s.lag1_pairs << " pairs): [t "
      << s.lag1_correlation(0) << " " << s.lag1_correlation(1) << " " << s.lag1_correlation(2) << ", r "
      << s.lag1_correlation(3) << " " << s.lag1_correlation(4) << " " << s.lag1_correlation(5) << "]\n";
  print_time_offset(out, "the rotations (colour)", s.rotation_time_offset, kRadToDeg, "deg");
  print_time_offset(out, "tz (depth)", s.depth_time_offset, 1e3, "mm");
}

void print_capture_timing(std::ostream& out, const CaptureTiming& timing, const Config& config, const RealtimeStats& run,
                          bool live) {
  if (!timing.gyro) {
    out << "  capture latency: not measured (no gyro: a replay's imu.txt or --imu, live the autopilot's ATTITUDE);"
           " the stamps stand, covered by covariance.colour_latency_sigma_s\n";
    return;
  }
  out << "  " << capture_latency_text(timing)
      << "; every motion stamped at its capture instant: the log's t_prev/t_curr and ODOMETRY time_usec are the "
         "stamps less the latency applied\n";
  const BodyConfig& b = config.body;
  const std::string mount =
      mount_text(timing, b.camera_roll_deg, b.camera_pitch_deg, b.camera_yaw_deg, config.latency.mount_warning_deg);
  out << "  " << (mount.empty() ? "mount: not measured (too little rotation about two axes)" : mount) << "\n";
  if (!timing.known) return;
  // Capture to the autopilot: the latency applied, then stamp to hand-over as measured live.
  const double stamp_to_output_ms = live && run.latency.count() > 0 ? run.latency.quantile_ms(0.5) : 0;
  const double worst_ms = live && run.latency.count() > 0 ? run.latency.quantile_ms(0.99) : 0;
  const double capture_ms = timing.applied_s * 1e3;
  out << std::fixed << std::setprecision(0) << "  autopilot settings: PX4 EKF2_EV_DELAY 0 ms once its TIMESYNC has "
         "converged (time_usec is the capture instant; before that PX4 stamps arrival: capture to arrival "
      << capture_ms + stamp_to_output_ms << " ms), EKF2_DELAY_MAX at least " << capture_ms + worst_ms + 20
      << " ms; ArduPilot VISO_DELAY_MS " << capture_ms + stamp_to_output_ms
      << " ms (capture to arrival: it maps time_usec to arrival)"
      << (live ? "" : " plus the link's transport and this computer's processing time, which a replay does not show")
      << "\n";
}

}  // namespace rgbdo
