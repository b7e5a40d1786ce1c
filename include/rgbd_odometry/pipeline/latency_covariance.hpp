#pragma once
// What an uncalibrated capture latency does to the reported motions, as a covariance term.
//
// A sensor's stamps are not its exposure times: each stream is captured some fixed time
// before it is stamped, and the colour and depth streams of an unsynchronised sensor (Kinect
// v1, Xtion) are captured at different times. Against TUM's motion capture, fr1's Kinect
// matches best with the colour taken 14-19 ms and the depth 39-42 ms before their stamps, at
// every frame rate tried (`eval/evaluate`'s time offsets;
// bench/MEASUREMENTS.md#covariance-consistency). The colour's
// reading is the tilt rotations', into which the depth's lag leaks through the split of the image
// motion; rz, which the depth does not enter, is on its stamps within a few ms
// (bench/MEASUREMENTS.md#drift-over-1-s-the-share-that-follows-the-change-of-rate). The colour term
// covers that leak as measured. The per-frame
// stamp jitter (covariance.timing_sigma_s) does not see such a latency: it is the same for
// every frame. What it does:
//  - colour, latency d_c: the pair measures the motion over [t_prev - d_c, t_curr - d_c]
//    instead of [t_prev, t_curr], off by d_c times the change of the camera's rate between the
//    two frames;
//  - depth, latency d_d behind the colour: each frame's depths are read d_d late, off by d_d
//    times dZ/dt; between two frames what is left is d_d times the change of rate, through
//    the fit (`depth_response`, PerturbationCovariance::depth_latency_response).
// Both are errors of the pair, not of a point: no number of points averages them away.
// With d ~ N(0, sigma^2), each pair gets, with D = the change of rate between its two frames,
//    per pair:  sigma_c^2 D D^T + sigma_d^2 G D D^T G^T (+ sigma_t^2 D_t D_t^T, below).
// D is estimated from this pair's and the previous pair's rates, whose own noise would
// inflate D D^T by their covariances: D D^T is shrunk by the share of it that noise explains.
// Across pairs the error telescopes: over a window it is d times the change of rate between
// the window's ends, which the per-pair terms, as a filter adds them, do not cover. Each pair
// therefore also carries its share of that over a consumer's integration window T_w,
//    over windows:  (dt / T_w) (sigma_c^2 (r r^T + r' r'^T) + sigma_d^2 G (...) G^T),
// r and r' this pair's and the previous pair's rates: summed over the pairs of a window, it is
// sigma^2 (2 x the mean r r^T), what the change of rate between its ends has on average.
// A pair restamped at the instant its rotations were taken (measured against a gyro) still has
// its translations from an instant between the colour's and the depth's: sigma_t (the depth's
// measured lag behind the colour) enters the translation block alone, D_t the translational
// part of the change of rate.
// Nor is its image shift moved with its stamps. The shift of the image (a point ahead at the
// inliers' mean inverse depth w: tx w + ry and ty w - rx) is what the colour measures most
// precisely, and it is the colour's own; the tilt rotations the gyro times are where the depth's
// lag leaks in (above). Against TUM fr1's motion capture the image shift matches best at the
// stamps and the tilt rotations 14 ms later, which is the latency applied; restamped by it, the
// pairs' image-shift errors double (src/pipeline/MEASUREMENTS.md#restamped-pairs-and-their-image-shift).
// Where the colour's own instant is told apart from the leak (the depth's lag measured as well),
// the image shift is retimed to the pair's times (pipeline/depth_clock.hpp) and only the
// retime's standard error and the interpolation's are left; where it is not, L is the whole
// restamp. Either way
//    image shift:  L^2 S S^T   in the (rx, ry) block,
// S the change of the image-shift rate (as rates about x and y), shrunk as D D^T is. It is 0
// where nothing is restamped (no gyro, or a sensor on its stamps).
#include <optional>

#include "rgbd_odometry/pipeline/pipeline_config.hpp"
#include "rgbd_odometry/core/geometry.hpp"

namespace rgbdo {

// One solved pair as the latency terms see it.
struct PairRate {
  Vector6d rate = Vector6d::Zero();          // xi / dt: m/s, then rad/s
  Matrix6d covariance = Matrix6d::Zero();    // of xi, before the latency terms
  double dt_s = 0;
  double inverse_depth = 0;                  // the inliers' mean 1/Z, 1/m (the image-shift term's w)
};

struct LatencySigmas {
  double colour_s = 0;             // sigma of the colour stream's latency behind its stamps
  double depth_s = 0;              // sigma of the depth stream's latency behind the colour
  double integration_window_s = 0;  // T_w; <= 0: no window share
  // sigma of the translations' instant apart from the rotations' (the translation alone: a
  // pair restamped at its rotations' measured instant, pipeline/capture_latency.hpp; 0 otherwise)
  double translation_s = 0;
  // How far the pair's image shift may sit from the pair's times (0: on them): the latency the
  // stamps were moved by (pipeline/capture_latency.hpp) where the image shift is not retimed to
  // them, the retime's standard error where it is (pipeline/depth_clock.hpp).
  double image_shift_off_s = 0;
  // How far the image shift was moved, R (0: not): by linear interpolation between the frames,
  // which errs by R (dt - R) / 2 times the camera's acceleration at each end, so the term also
  // takes (R (1 - R/dt))^2 / 2 (a change of rate shared equally by the two ends' pairs).
  double image_shift_retime_s = 0;
  // The pair carries the image-shift term (which needs the inliers' mean inverse depth).
  bool image_shift_term() const { return image_shift_off_s != 0 || image_shift_retime_s != 0; }
};

inline LatencySigmas latency_sigmas(const CovarianceConfig& c) {
  return {c.colour_latency_sigma_s, c.depth_latency_sigma_s, c.integration_window_s, 0};
}

// The latency covariance of pair `curr`; previous: the pair before it, when the two are
// contiguous (no gap). Without it the change of rate is taken to be as large as the rate.
// depth_response: PerturbationCovariance::depth_latency_response of this pair.
Matrix6d latency_covariance(const LatencySigmas& sigmas, const Matrix6d& depth_response, const PairRate& curr,
                            const std::optional<PairRate>& previous);

}  // namespace rgbdo
