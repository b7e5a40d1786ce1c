#pragma once
// The standard error of the depth's lag behind the colour, measured against the gyro with what
// the two streams' latency fits share taken out.
//
// Each stream's latency is fitted against the gyro on its own (capture_latency.hpp), and each
// fit errs by the gyro's noise and by how far its samples miss the motion between them. The two
// fits read the same gyro over nearly the same intervals, so their errors are nearly the same
// and cancel in their difference, the lag: their two standard errors together overstate its
// (ICL-NUIM's rendered frames, six gyro seeds: each latency 0.0-0.2 ms +- 0.2 ms, the two equal
// to the printed 0.1 ms every time). What the lag's error is made of shows in the pairs'
// differences. At the colour's latency c, a pair's depth rotation's residual less its colour
// rotation's,
//     y = (theta_d - G_d(c)) - (theta_c - G_c(c)) = L g + noise,   g = dG_d/dd at c,
// G a stream's gyro integral over its interval moved by d: the gyro's noise over the shared
// interval cancels in y, and what is left is the two rotations' own errors. Least squares
// through the origin, L = sum g.y / sum g.g, its standard error sqrt(s^2 / sum g.g) with s^2
// the scatter of y about L g (three components a pair, one parameter). Once enough pairs are
// in, a pair beyond chi-square(3)'s 99.9 % point of that scatter is a failed fit's and left
// out. The lag is the sensor's own: nothing fades.
//
// L itself weighs the axes by the gyro's changes of rate, not as the two fits do, and on a
// Kinect its axes differ (TUM fr1_xyz: 11.5, 9.8 and 1.8 ms about the body's x, y and z, where
// the depth alignment's turn about the vertical follows the features'): 7-8 ms against the two
// fits' 14.2. The lag used stays the two fits' difference; this gives its standard error.
#include <Eigen/Core>
#include <cstdint>

#include "rgbd_odometry/core/recent_median.hpp"

namespace rgbdo {

class DepthLagFit {
 public:
  // One pair's difference y and slope g (body frame, rad and rad/s).
  void add(const Eigen::Vector3d& y, const Eigen::Vector3d& g);
  // Enough pairs for the scatter and a slope that tells L from none.
  bool known() const;
  double lag_s() const { return sum_gg_ > 0 ? sum_gy_ / sum_gg_ : 0.0; }
  double sigma_s() const;
  std::uint64_t pairs() const { return pairs_; }
  std::uint64_t rejected() const { return rejected_; }

 private:
  double scatter() const;  // per component, about L g
  double gate_scatter() const;  // what the gate judges by
  RecentMedian<31> judged_;       // the last pairs' squared residuals, let in or not
  double sum_gg_ = 0, sum_gy_ = 0, sum_yy_ = 0;
  std::uint64_t pairs_ = 0, rejected_ = 0;
};

}  // namespace rgbdo
