#pragma once
// The depth frames' lag beyond their stamps, taken out of the motion along the optical axis.
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
// Each frame gets a shift s = lag × its own velocity along z (the mean of the last few pairs'
// velocities, the newest included: one pair's own is too noisy, the change of two of them
// doubling each pair's error), and a motion measured between two frames' depth instants is
// carried to their colour instants by Tz(-s_a) · M · Tz(s_b). Both the frame pairs and the
// keyframe's measurements are carried, so the chain and its pull agree.
//
// The lag is the depth's behind its colour frame's stamps, and the motion is carried to the
// pair's times: the stamps, or, where the capture clock has moved them to the capture instants
// against a gyro (pipeline/capture_latency.hpp), the stamps less the latency applied, which
// leaves lag − applied to carry. On fr1's Kinect the gyro's latency (13 ms) is the tilt
// rotations', into which the depth's lag already leaks while the image shift sits on the stamps
// (MEASUREMENTS.md, "Restamped pairs and their image shift"): carried the whole 17 ms there the
// restamped 1-s drift grew by a tenth, carried 17 − 13 it did not.
#include <array>

#include <Eigen/Geometry>

namespace rgbdo {

class DepthClock {
 public:
  // lag_s: depth.lag_beyond_stamps_s; 0 leaves every motion as it is, restamped or not.
  explicit DepthClock(double lag_s) : lag_s_(lag_s) {}

  // A good pair's motion, as measured (between the depth instants): the newer frame's shift is
  // updated from its velocity; the motion between the pair's times is returned. restamped_s:
  // the latency the capture clock applies to the pair's times (0 without a gyro).
  Eigen::Isometry3d carry(const Eigen::Isometry3d& measured, double dt_s, double restamped_s);
  // The newer frame's shift of the last carry(), metres along its optical axis (0 after forget()).
  double frame_shift_m() const { return shift_m_; }
  // A gap or a failed pair: the velocity before it says nothing about the frames after.
  void forget();

 private:
  static constexpr int kVelocityPairs = 3;  // measured against 1 and 5: MEASUREMENTS.md
  double lag_s_;
  std::array<double, kVelocityPairs> velocity_z_{};
  int count_ = 0;  // velocities held since the last forget(), up to kVelocityPairs
  int next_ = 0;
  double shift_m_ = 0;
};

// A motion measured between two frames' depth instants (a's shift s_a, b's s_b, each along its
// own optical axis) carried to their colour instants: Tz(-s_a) · measured · Tz(s_b).
Eigen::Isometry3d at_colour_instants(const Eigen::Isometry3d& measured, double shift_a_m, double shift_b_m);

}  // namespace rgbdo
