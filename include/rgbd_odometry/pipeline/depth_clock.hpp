#pragma once
// The depth frames' lag beyond their stamps, taken out of the motion: along the optical axis,
// and where it leaks into the tilt rotations, along the slide.
//
// A keypoint's depth is read from a depth frame captured `lag` earlier (negative: later) than
// the stamps say relative to its colour frame. Depth is what places the points along the
// optical axis, so a pair's translation along it is measured between the two depth instants
// while the rest of its motion is measured between the colour ones: its z is off by
// lag × (the camera's velocity along z at the newer frame − at the older one). Over a chain of
// pairs the error telescopes to lag × the change of velocity across the chain: the share of a
// Kinect's 1-s drift that follows the change of rate (src/pipeline/MEASUREMENTS.md, "The depth's
// lag beyond its stamps"). The per-keypoint timing compensation (depth.compensate_timing) cannot
// take it out: it carries both frames with one velocity, the pair's, and the difference cancels.
//
// The lag leaks into the tilt rotations too (about the image's x and y axes), through the
// split of the image's motion: the image shift of a point ahead at inverse depth w
// (tx w + ry, ty w − rx) is the colour's own and on its stamps, while the slide (tx w − ry,
// ty w + rx), which only parallax tells apart, is measured 20–24 ms late on fr1's Kinect and
// takes the tilt with it (its rotations match the motion capture, and a gyro, 13 ms before the
// stamps). The tilt is carried by tilt_lag × the frame's turning rate with the sideways
// translation taking the opposite share, so that the image shift stays where it was measured
// (MEASUREMENTS.md, "The tilt's lag, carried along the slide").
//
// Each frame gets a shift: lag × its own velocity along z, and a turn tilt_lag × its turning
// rate about x and y with the translation that keeps its image shift at its inliers' mean
// inverse depth (the rates are the means of the last few pairs', the newest included: one
// pair's own is too noisy, the change of two of them doubling each pair's error). A motion
// measured between two frames' depth instants is carried to their colour instants by
// S_a⁻¹ · M · S_b. Both the frame pairs and the keyframe's measurements are carried, so the
// chain and its pull agree.
//
// The lag is the depth's behind its colour frame's stamps, and the motion is carried to the
// pair's times: the stamps, or, where the capture clock has moved them to the capture instants
// against a gyro (pipeline/capture_latency.hpp), the stamps less the latency applied, which
// leaves lag − applied to carry. On fr1's Kinect the gyro's latency (13 ms) is the tilt
// rotations', into which the depth's lag already leaks while the image shift sits on the stamps
// (MEASUREMENTS.md, "Restamped pairs and their image shift"): carried the whole 17 ms there the
// restamped 1-s drift grew by a tenth, carried 17 − 13 it did not. And where a gyro times the
// rotations, no tilt is carried: the gyro's restamp is their instant.
//
// Their instant is not the image shift's. Where the capture clock tells the colour's own
// latency apart (capture_latency.hpp), the image shift is moved the rest of the way, R: the
// newer frame's pose goes back R / dt of this pair's image shift, as a sideways translation
// (the rotations stay at the gyro's instant). That is the chain's image shift read R earlier
// by linear interpolation between the frames, so a pair becomes (1 − R/dt) of its own image
// shift and R/dt of the one before, and over a chain the shift telescopes to the ends' frames.
#include <array>

#include <Eigen/Geometry>

namespace rgbdo {

class DepthClock {
 public:
  // lag_s: depth.lag_beyond_stamps_s; tilt_lag_s: depth.tilt_lag_beyond_stamps_s. Both 0 leave
  // every motion as it is, restamped or not, unless an image shift is retimed (carry()).
  explicit DepthClock(double lag_s, double tilt_lag_s = 0) : lag_s_(lag_s), tilt_lag_s_(tilt_lag_s) {}

  // A good pair's motion, as measured (between the depth instants): the newer frame's shift is
  // updated from its rates; the motion between the pair's times is returned. restamped_s:
  // the latency the capture clock applies to the pair's times (0 without a gyro).
  // rotations_timed: a gyro times the rotations; the tilt lag is then not carried.
  // inverse_depth: the newer frame's inliers' mean 1/Z (neither the tilt nor the image shift is
  // carried without it). image_shift_retime_s: how far the image shift is moved to the pair's
  // times (CaptureClock::image_shift_retime_s; 0: it stays where it was measured).
  Eigen::Isometry3d carry(const Eigen::Isometry3d& measured, double dt_s, double restamped_s,
                          bool rotations_timed = false, double inverse_depth = 0, double image_shift_retime_s = 0);
  // The newer frame's shift of the last carry() (identity after forget()).
  const Eigen::Isometry3d& frame_shift() const { return shift_; }
  // A gap or a failed pair: the velocity before it says nothing about the frames after.
  void forget();

 private:
  static constexpr int kVelocityPairs = 3;  // measured against 1 and 5: MEASUREMENTS.md
  double lag_s_, tilt_lag_s_;
  std::array<Eigen::Vector3d, kVelocityPairs> rates_{};  // v_z, w_x, w_y of the last pairs
  int count_ = 0;  // rates held since the last forget(), up to kVelocityPairs
  int next_ = 0;
  Eigen::Isometry3d shift_ = Eigen::Isometry3d::Identity();
};

// A motion measured between two frames' depth instants carried to their colour instants by the
// two frames' shifts: shift_a⁻¹ · measured · shift_b.
Eigen::Isometry3d at_colour_instants(const Eigen::Isometry3d& measured, const Eigen::Isometry3d& shift_a,
                                     const Eigen::Isometry3d& shift_b);

}  // namespace rgbdo
