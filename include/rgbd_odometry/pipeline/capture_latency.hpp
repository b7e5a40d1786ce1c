#pragma once
// When the frames were taken, learnt from the autopilot's gyro.
//
// A sensor stamps a frame some time after it exposed it (fr1's Kinect: 15-17 ms), and no image
// shows how long. The autopilot's gyro does: the camera's rotation between two frames, turned
// into the body frame by the configured mount, equals the gyro's rate integrated over the
// interval the frames were really taken in. For each candidate latency d on a grid
// (latency.min_s .. max_s, 1 ms apart) every pair k gives the residual
//     r_k(d) = R_body_camera theta_k - integral of the gyro over [t_prev - d, t_curr - d]
//            = -b dt_k + noise        (b: the gyro's bias, constant per axis)
// every pair weighing the same (solve() says why). The cost J(d) = sum_k |r_k|^2 with b
// solved in closed form per d is kept as running sums (allocated once), so each pair costs a
// fixed amount of work. The latency is J's minimum (refined between grid points by a
// parabola); its standard error is sqrt(2 s^2 / J''), s^2 the residuals' own scatter.
// Only a change of rate across a pair says anything about d (dr/dd is that change): a camera
// at rest is left out and forgets nothing, so the estimate holds while the vehicle waits; a
// turning camera's older pairs fade over latency.memory_s, so a slowly changing latency is
// followed. A pair far from the estimate (a failed fit) is left out.
//
// The gyro changes the time, never the motion: the autopilot's filter has its gyro already,
// and a motion fused with it would carry errors twice.
//
// The same pairs measure the camera's mount: the rotation that carries the camera's rates onto
// the gyro's (with the bias as offset) is an absolute-orientation fit (core/umeyama.hpp) at the
// estimated latency, over the last pairs that turned the camera.
#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "rgbd_odometry/pipeline/pipeline_config.hpp"
#include "rgbd_odometry/core/gyro.hpp"
#include "rgbd_odometry/core/pair_result.hpp"
#include "rgbd_odometry/core/recent_median.hpp"
#include "rgbd_odometry/pipeline/depth_lag_fit.hpp"

namespace rgbdo {

struct LatencyEstimate {
  bool known = false;     // a minimum inside the searched range, with a finite standard error
  double latency_s = 0;   // stamp minus capture instant, on the gyro's clock
  double sigma_s = 0;     // its standard error
  // How far the rotation axes' own latencies lie from it (rms, weighed by their information,
  // less their noise): one latency applied to a sensor whose streams enter the axes
  // differently leaves that much.
  double axis_spread_s = 0;
  double scatter = 0;     // the fit's reduced chi-square (1: the pairs scatter as their covariance says)
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();  // rad/s, body, at that latency
  std::uint64_t pairs = 0;     // pairs the estimate has seen
  std::uint64_t rejected = 0;  // pairs too far from it to be believed (a failed fit), left out
  std::uint64_t at_rest = 0;   // pairs of a camera at rest: nothing to learn from them
  std::uint64_t uncovered = 0; // pairs the gyro samples did not cover (a gap, before the first)
};

// The camera's mount as the gyro sees it, in body.*'s terms.
struct MountEstimate {
  bool known = false;  // enough rotation about two axes at least
  double roll_deg = 0, pitch_deg = 0, yaw_deg = 0;
  int pairs = 0;
};

class CaptureLatencyEstimator {
 public:
  CaptureLatencyEstimator(const LatencyConfig& config, const Eigen::Matrix3d& R_body_camera);

  // Gyro samples in time order (older or equal stamps than the newest held are dropped).
  void add_gyro(std::span<const GyroSample> samples);
  // A solved pair on the stamps' timeline (its colour stamps) and its rotation vector (camera
  // frame). Held until the gyro covers every offset searched.
  void add_pair(std::int64_t t_prev_ns, std::int64_t t_curr_ns, const Eigen::Vector3d& rotation);
  // The gyro samples a pair stamped t_curr_ns needs, up to this time.
  std::int64_t gyro_needed_until_ns(std::int64_t t_curr_ns) const;

  const LatencyEstimate& estimate() const { return estimate_; }
  // Fitted now, from the pairs held (buffers sized once).
  MountEstimate mount();
  // The gyro's rotation over [from, to] (body frame, bias included); nullopt where the samples
  // held do not cover it without a gap.
  std::optional<Eigen::Vector3d> integral_over(std::int64_t from_ns, std::int64_t to_ns) const;

 private:
  struct Pair {
    std::int64_t t_prev_ns = 0, t_curr_ns = 0;
    Eigen::Vector3d rotation = Eigen::Vector3d::Zero();  // camera frame
  };
  struct Gyro {
    std::int64_t t_ns = 0;
    Eigen::Vector3d rate = Eigen::Vector3d::Zero();
    Eigen::Vector3d integral = Eigen::Vector3d::Zero();  // since the segment's first sample
    std::uint64_t segment = 0;  // samples without a gap between them share one
  };
  struct Integral {
    Eigen::Vector3d value;
    std::uint64_t segment;
  };
  // The gyro's running integral at t; nullopt outside the samples held or inside a gap.
  std::optional<Integral> integral_at(std::int64_t t_ns) const;
  const Gyro& gyro(std::size_t i) const { return gyro_[(gyro_first_ + i) % gyro_.size()]; }
  void process(const Pair& p);
  void solve();

  LatencyConfig config_;
  Eigen::Matrix3d R_body_camera_;
  int offsets_ = 0;  // grid points, 1 ms apart from config_.min_s
  // Running sums per grid offset and body axis (weights w, intervals dt, residuals r at b = 0):
  // sum w dt^2 (the same for every offset), sum w dt r, sum w r^2.
  Eigen::Vector3d sum_tt_ = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> sum_tr_, sum_rr_;
  double weight_sum_ = 0;  // pairs, faded as the sums are
  // The squared residuals of the last pairs judged against the estimate, let in or not.
  static constexpr std::size_t kJudgedPairs = 31;
  RecentMedian<kJudgedPairs> judged_r2_;
  // Whether a pair's residual r at the estimate (grid index k of its residuals over the offsets)
  // lies beyond what the estimate predicts: a failed fit's.
  bool outside_gate(const Eigen::Vector3d& r, const std::vector<Eigen::Vector3d>& residual, int k) const;
  std::vector<Gyro> gyro_;  // ring
  std::size_t gyro_first_ = 0, gyro_count_ = 0;
  std::vector<Pair> waiting_;  // ring: pairs the gyro does not cover yet
  std::size_t waiting_first_ = 0, waiting_count_ = 0;
  std::vector<Pair> recent_;  // ring: the last pairs that turned the camera, for the mount
  std::size_t recent_next_ = 0, recent_count_ = 0;
  std::vector<Eigen::Vector3d> residual_;  // one pair's, per offset
  std::vector<Eigen::Vector3d> mount_camera_, mount_body_;  // the mount fit's rates
  LatencyEstimate estimate_;
};

// What the latency terms of the covariance take from the measurement (latency_covariance.hpp);
// nullopt where the priors stand.
struct MeasuredLatencySigmas {
  std::optional<double> colour_s, depth_s, translation_s;
  double applied_s = 0;  // the latency the stamps are moved by
  bool gyro = false;     // a gyro times the rotations (the depth clock carries no tilt lag)
  // How far the pairs' image shift is to be moved to their times (image_shift_retime_s()) and
  // the standard error of that; nullopt while it is not measured (the image shift then stays
  // on its stamps and the covariance covers the whole restamp, LatencySigmas::image_shift_off_s).
  std::optional<double> image_shift_retime_s;
  double image_shift_retime_sigma_s = 0;
};

// The latency applied: each pair stamped at its frames' capture instants. Lives on the
// estimation thread, next to the PairEstimator whose covariance it informs.
class CaptureClock {
 public:
  // feed: the gyro's samples (live: the autopilot's; a replay: imu.txt), null for none.
  CaptureClock(const PipelineConfig& config, GyroFeed* feed);

  // What the covariance should carry instead of covariance.colour_latency_sigma_s: the colour
  // latency's standard error, the axes' spread and what is not applied yet; nullopt while the
  // latency is not measured.
  std::optional<double> colour_latency_sigma_s() const;
  // Instead of covariance.depth_latency_sigma_s: the depth's lag behind the colour, which is not
  // corrected (rms with its standard error); nullopt while it is not measured.
  std::optional<double> depth_latency_sigma_s() const;
  // The depth alignment's rotations' latency less the pairs': the depth's lag behind the colour
  // beyond their stamps; nullopt while either is not measured.
  std::optional<double> depth_lag_s() const;
  // Its standard error: of the pairs' differences against the gyro (depth_lag_fit.hpp), which
  // the errors the two latency fits share do not enter.
  double depth_lag_sigma_s() const;
  // The colour image's own latency behind its stamps, told apart from the depth's lag that leaks
  // into the tilt rotations the gyro times. A tilt from the features is half the image shift
  // (the colour's, at its latency L_c) less half the slide (the depth's, at L_d): its latency,
  // the one measured, is (L_c + L_d) / 2, so L_c = 2 L - L_d. fr1's Kinect: L 13.2 ms, L_d 27.4,
  // L_c -1.1 (its image shift matches the motion capture best at the stamps); a sensor whose
  // streams are late together reads L_c = L. nullopt while the depth's lag is not measured or
  // L_c is less certain than latency.converged_sigma_s.
  // (src/pipeline/MEASUREMENTS.md#the-image-shift-moved-to-the-capture-instants)
  std::optional<double> colour_image_latency_s() const;
  double colour_image_latency_sigma_s() const;  // of 2 L - L_d = L - lag
  // How far the image shift is moved to the pairs' times: the latency applied less L_c, shrunk
  // towards 0 by L_c's standard error; nullopt where L_c is not known or
  // latency.retime_image_shift is off.
  std::optional<double> image_shift_retime_s() const;
  // All of them, for PairEstimator::set_latency_sigmas.
  MeasuredLatencySigmas latency_sigmas() const;
  // Learns from a finished pair (stamps as the sensor gave them) and restamps it at the
  // capture instants: t_prev at the instant its frame was given as the previous pair's current
  // frame, t_curr at the latency applied now. Fills r.timing.
  void stamp(PairResult& r);
  bool active() const { return feed_ != nullptr; }
  const LatencyEstimate& estimate() const { return estimator_.estimate(); }
  const LatencyEstimate& depth_estimate() const { return depth_estimator_.estimate(); }

 private:
  LatencyConfig config_;
  GyroFeed* feed_;
  CaptureLatencyEstimator estimator_;        // the pairs' rotations: the colour's latency
  CaptureLatencyEstimator depth_estimator_;  // the depth alignment's rotations: the depth's
  DepthLagFit lag_;                          // the two rotations' difference: the depth's lag
  Eigen::Matrix3d R_body_camera_;
  // The pair's depth rotation less its colour rotation, each less the gyro's over its own
  // interval at the colour's latency, into lag_ (nothing where the gyro does not cover both).
  void learn_lag(const PairResult& r, std::int64_t stamp_prev_ns, std::int64_t stamp_curr_ns);
  std::vector<GyroSample> taken_;  // one take()'s buffer, sized once
  double applied_s_ = 0;
  CaptureTiming timing_;  // as of the last pair, its mount refreshed every kMountEveryPairs
  int pairs_since_mount_ = 0;
  std::optional<std::int64_t> last_curr_stamp_ns_;  // the last pair's t_curr as the sensor stamped it
  std::int64_t last_curr_shift_ns_ = 0;             // and the latency it was given
};

}  // namespace rgbdo
