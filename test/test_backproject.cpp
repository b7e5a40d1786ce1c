#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>
#include <opencv2/calib3d.hpp>

#include "rgbd_odometry/pipeline/backproject.hpp"
#include "rgbd_odometry/pipeline/depth_clock.hpp"

namespace rgbdo {
namespace {

CameraConfig fr1_camera() {
  CameraConfig c;
  c.fx = 517.306408;
  c.fy = 516.469215;
  c.cx = 318.643040;
  c.cy = 255.313989;
  c.distortion = {0.262383, -0.953104, -0.005358, 0.002628, 1.163314};
  return c;
}

cv::Mat plane(double z) { return cv::Mat(480, 640, CV_32F, cv::Scalar(z)); }

TEST(BackProject, InvertsTheDistortedPinholeProjection) {
  // GIVEN points on the plane Z = 2 projected through the fr1 lens model
  CameraConfig cam = fr1_camera();
  const std::vector<cv::Point3d> points{{0, 0, 2}, {0.8, 0.5, 2}, {-0.9, -0.6, 2}, {0.3, -0.7, 2}};
  std::vector<cv::Point2d> pixels;
  const cv::Mat K = (cv::Mat_<double>(3, 3) << cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1);
  cv::projectPoints(points, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K,
                    cv::Mat(1, 5, CV_64F, cam.distortion.data()), pixels);
  std::vector<cv::KeyPoint> kps;
  for (const auto& p : pixels) kps.emplace_back(cv::Point2f(static_cast<float>(p.x), static_cast<float>(p.y)), 7.f);
  // WHEN they are back-projected with the plane's depth image
  KeypointBackProjector bp(cam, DepthConfig{});
  KeypointGeometry g;
  bp.compute(kps, plane(2.0), g);
  // THEN the 3-D points come back (float keypoint coordinates: ~1e-5 px)
  for (size_t i = 0; i < points.size(); ++i) {
    ASSERT_GT(g.depth_m[i], 0);
    EXPECT_NEAR(g.normalized[i].x() * g.depth_m[i], points[i].x, 1e-4);
    EXPECT_NEAR(g.normalized[i].y() * g.depth_m[i], points[i].y, 1e-4);
    EXPECT_DOUBLE_EQ(g.depth_m[i], 2.0);
  }
  // Without the distortion model the corner point would be off by centimetres.
  EXPECT_GT(std::abs((pixels[2].x - cam.cx) / cam.fx * 2.0 - points[2].x), 0.01);
}

TEST(BackProject, TheFastUndistortionReadsTheExactInversion) {
  // GIVEN fr1's lens and pixels all over its image, on it and off it
  const CameraConfig cam = fr1_camera();
  cv::RNG rng(7);
  std::vector<cv::Point2f> pixels;
  for (int k = 0; k < 20000; ++k)
    pixels.emplace_back(static_cast<float>(rng.uniform(0.0, cam.width - 1.0)),
                        static_cast<float>(rng.uniform(0.0, cam.height - 1.0)));
  const std::vector<cv::Point2f> corners{{0, 0}, {639, 0}, {0, 479}, {639, 479}, {638.9f, 478.9f}};
  const std::vector<cv::Point2f> off_image{{-3.5f, 100}, {645, 240}, {320, -0.25f}, {320, 490}};
  pixels.insert(pixels.end(), corners.begin(), corners.end());
  pixels.insert(pixels.end(), off_image.begin(), off_image.end());
  // WHEN they are undistorted from the grid and by the converged inversion itself
  std::vector<cv::Point2f> fast, exact;
  PixelUndistorter(cam).undistort(pixels, fast);
  undistort_pixels_exactly(cam, pixels, exact);
  // THEN the grid's rays are the exact ones within 0.008 px (measured: 0.0062 px at worst; a grid
  // node every 4 px), and pixels off the image are inverted exactly
  ASSERT_EQ(fast.size(), pixels.size());
  double worst_px = 0;
  for (size_t k = 0; k < pixels.size(); ++k)
    worst_px = std::max({worst_px, std::abs(fast[k].x - exact[k].x) * cam.fx, std::abs(fast[k].y - exact[k].y) * cam.fy});
  EXPECT_LT(worst_px, 0.008);
  for (size_t k = pixels.size() - off_image.size(); k < pixels.size(); ++k) {
    EXPECT_EQ(fast[k].x, exact[k].x);
    EXPECT_EQ(fast[k].y, exact[k].y);
  }
  // ... while OpenCV's default inversion (5 steps) leaves more than 0.05 px there: the grid is
  // nearer the lens model than what it replaces.
  std::vector<cv::Point2f> five_steps;
  const cv::Mat K = (cv::Mat_<double>(3, 3) << cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1);
  cv::undistortPoints(pixels, five_steps, K, cv::Mat(1, 5, CV_64F, const_cast<double*>(cam.distortion.data())));
  double worst_five_px = 0;
  for (size_t k = 0; k < pixels.size(); ++k) worst_five_px = std::max(worst_five_px, std::abs(five_steps[k].x - exact[k].x) * cam.fx);
  EXPECT_GT(worst_five_px, 0.05);
  std::printf("grid: %.5f px at worst; OpenCV's 5 steps: %.5f px\n", worst_px, worst_five_px);
}

TEST(BackProject, WithoutDistortionTheRayIsThePinholes) {
  // GIVEN a lens without distortion (ICL-NUIM's, TUM fr3's)
  CameraConfig cam = fr1_camera();
  cam.distortion = {0, 0, 0, 0, 0};
  // WHEN a pixel is undistorted
  std::vector<cv::Point2f> ray;
  PixelUndistorter(cam).undistort({{100.25f, 400.5f}}, ray);
  // THEN it is the pinhole's division
  ASSERT_EQ(ray.size(), 1u);
  EXPECT_NEAR(ray[0].x, (100.25 - cam.cx) / cam.fx, 1e-6);
  EXPECT_NEAR(ray[0].y, (400.5 - cam.cy) / cam.fy, 1e-6);
}

TEST(BackProject, RejectsOcclusionEdgesHolesAndOutOfRange) {
  cv::Mat depth = plane(1.5);
  depth.colRange(320, 640).setTo(3.0);  // a depth step at column 320
  depth.at<float>(100, 100) = 0;         // a hole
  depth.rowRange(400, 480).setTo(9.0);   // beyond max_m
  const std::vector<cv::KeyPoint> kps{{{200.f, 200.f}, 7.f}, {{319.f, 200.f}, 7.f}, {{101.f, 101.f}, 7.f},
                                      {{500.f, 450.f}, 7.f}, {{1.f, 1.f}, 7.f}};
  KeypointBackProjector bp(fr1_camera(), DepthConfig{});
  KeypointGeometry g;
  bp.compute(kps, depth, g);
  EXPECT_DOUBLE_EQ(g.depth_m[0], 1.5);  // clean surface
  EXPECT_EQ(g.depth_m[1], 0);           // 1 px from the step
  EXPECT_EQ(g.depth_m[2], 0);           // hole in the neighbourhood
  EXPECT_EQ(g.depth_m[3], 0);           // out of range
  EXPECT_EQ(g.depth_m[4], 0);           // neighbourhood leaves the image
}

// A depth image sloping along both image axes: Z = 1.5 + 0.002 u - 0.0015 v metres, so that
// where it is read shows in the depth.
cv::Mat ramp() {
  cv::Mat d(480, 640, CV_32F);
  for (int v = 0; v < d.rows; ++v)
    for (int u = 0; u < d.cols; ++u) d.at<float>(v, u) = static_cast<float>(1.5 + 0.002 * u - 0.0015 * v);
  return d;
}

TEST(BackProject, ReadsTheDepthWhereItsImageRegistersAgainstTheColour) {
  // GIVEN a depth image that shows each surface 0.77 px left of and 1.11 px below where the
  // colour shows it (TUM fr1's Kinect), and keypoints at whole and fractional pixels
  DepthConfig registered;
  registered.registration_x_px = 0.77;
  registered.registration_y_px = -1.11;
  const std::vector<cv::KeyPoint> kps{{{200.f, 150.f}, 7.f}, {{321.4f, 260.7f}, 7.f}, {{450.25f, 333.5f}, 7.f}};
  KeypointGeometry as_registered, unregistered;
  KeypointBackProjector(fr1_camera(), registered).compute(kps, ramp(), as_registered);
  KeypointBackProjector(fr1_camera(), DepthConfig{}).compute(kps, ramp(), unregistered);
  for (size_t i = 0; i < kps.size(); ++i) {
    const double u = kps[i].pt.x, v = kps[i].pt.y;
    // THEN each depth is the ramp's at the keypoint moved by the registration (the slope
    // carries it from the nearest pixel), and the unregistered reading is the keypoint's own
    EXPECT_NEAR(as_registered.depth_m[i], 1.5 + 0.002 * (u - 0.77) - 0.0015 * (v + 1.11), 1e-5) << i;
    EXPECT_NEAR(unregistered.depth_m[i], 1.5 + 0.002 * u - 0.0015 * v, 1e-5) << i;
    // and the ray is the colour's: the registration moves where the depth is read, not the point
    EXPECT_EQ(as_registered.normalized[i], unregistered.normalized[i]);
  }
}

TEST(BackProject, TimingCompensationMovesDepthToTheColourInstant) {
  // GIVEN a camera approaching a wall at 0.3 m/s; the wall is 2 m away at t = 0.
  // Depth images are taken 15 ms before (prev) and 15 ms after (curr) their colour images.
  const double v = 0.3, dt = 1.0 / 30, off = 0.015;
  const auto wall_at = [&](double t) { return plane(2.0 - v * t); };
  CameraConfig cam = fr1_camera();
  cam.distortion = {0, 0, 0, 0, 0};
  KeypointBackProjector bp(cam, DepthConfig{});
  const std::vector<cv::KeyPoint> kps{{{300.f, 200.f}, 7.f}};
  KeypointGeometry prev, curr;
  bp.compute(kps, wall_at(-off), prev);
  bp.compute(kps, wall_at(dt + off), curr);
  const FrameTimes prev_t{0, -15'000'000}, curr_t{33'333'333, 33'333'333 + 15'000'000};
  const std::vector<Match> matches{{0, 0, 0}};
  PointPairs raw, compensated;
  build_point_pairs(matches, prev, prev_t, curr, curr_t, nullptr, raw);
  MotionPrior prior;
  prior.velocity_mps = Eigen::Vector3d(0, 0, v);
  build_point_pairs(matches, prev, prev_t, curr, curr_t, &prior, compensated);
  ASSERT_EQ(raw.size(), 1u);
  // THEN the raw depths are 4.5 mm off each, in opposite directions; compensated they are exact
  EXPECT_NEAR(raw.prev[0].z(), 2.0 + v * off, 1e-6);
  EXPECT_NEAR(raw.curr[0].z(), 2.0 - v * (dt + off), 1e-6);
  EXPECT_NEAR(compensated.prev[0].z(), 2.0, 1e-6);
  EXPECT_NEAR(compensated.curr[0].z(), 2.0 - v * dt, 1e-6);
}

TEST(BackProject, PairsNeedDepthOnBothSides) {
  cv::Mat with_hole = plane(1.0);
  with_hole.at<float>(50, 50) = 0;
  const std::vector<cv::KeyPoint> kps{{{50.f, 50.f}, 7.f}, {{200.f, 200.f}, 7.f}};
  KeypointBackProjector bp(fr1_camera(), DepthConfig{});
  KeypointGeometry a, b;
  bp.compute(kps, with_hole, a);
  bp.compute(kps, plane(1.0), b);
  PointPairs pairs;
  build_point_pairs({{0, 0, 0}, {1, 1, 0}}, a, {}, b, {}, nullptr, pairs);
  ASSERT_EQ(pairs.size(), 1u);
  EXPECT_EQ(pairs.match_index[0], 1);
}


// The depth clock (pipeline/depth_clock.hpp). A camera whose velocity along its optical axis
// is v(t), depth read `lag` before the colour: a pair's z measured between the depth instants,
// the rest between the colour ones.
Eigen::Isometry3d turn_and_move(double angle_rad, const Eigen::Vector3d& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(angle_rad, Eigen::Vector3d(0.3, 1.0, 0.2).normalized()).toRotationMatrix();
  T.translation() = t;
  return T;
}

Eigen::Isometry3d along_z(double s) { return Eigen::Isometry3d(Eigen::Translation3d(0, 0, s)); }

TEST(DepthClock, CarriesAMotionAsTheTwoFramesShiftsAlongTheirOwnOpticalAxes) {
  // Against the composition written out: Tz(-a) M Tz(b).
  const Eigen::Isometry3d M = turn_and_move(0.2, {0.01, -0.02, 0.03});
  const double a = 0.004, b = -0.007;
  const Eigen::Isometry3d expected =
      Eigen::Translation3d(0, 0, -a) * M * Eigen::Translation3d(0, 0, b);
  const Eigen::Isometry3d carried = at_colour_instants(M, along_z(a), along_z(b));
  EXPECT_LT((carried.matrix() - expected.matrix()).cwiseAbs().maxCoeff(), 1e-15);
  const Eigen::Isometry3d none = Eigen::Isometry3d::Identity();
  EXPECT_TRUE(at_colour_instants(M, none, none).isApprox(M, 1e-15));
}

TEST(DepthClock, TakesTheLagOutOfAChainOfPairsWhoseVelocityChanges) {
  // Velocity along z held for 6 pairs at a time, then stepped. A step reaches the velocities
  // the clock averages (the measured ones, lag and all) for 3 pairs; after that every pair's z
  // comes back as taken between the colour instants, and the chain's error, lag x the change
  // of velocity, goes with it.
  const double lag = 0.017, dt = 1.0 / 30;
  const double segments[] = {0.0, 0.3, -0.2, 0.1};
  DepthClock clock(lag);
  double measured_sum = 0, carried_sum = 0, true_sum = 0, v_prev = segments[0];
  for (double vk : segments) {
    for (int i = 0; i < 6; ++i) {
      // The depth instants trail the colour's by lag: z over the pair is off by lag (v_k - v_k-1).
      const double true_z = vk * dt;
      const double measured_z = true_z - lag * (vk - v_prev);
      const Eigen::Isometry3d c = clock.carry(turn_and_move(0.0, {0.002, 0.001, measured_z}), dt, 0.0);
      EXPECT_DOUBLE_EQ(c.translation().x(), 0.002);  // only the optical axis moves
      EXPECT_DOUBLE_EQ(c.translation().y(), 0.001);
      if (i >= 4) {
        EXPECT_NEAR(c.translation().z(), true_z, 1e-15) << vk << " pair " << i;
        EXPECT_NEAR(clock.frame_shift().translation().z(), lag * vk, 1e-15);
        EXPECT_TRUE(clock.frame_shift().linear().isIdentity(0));  // no tilt lag: no turn
      }
      measured_sum += measured_z;
      carried_sum += c.translation().z();
      true_sum += true_z;
      v_prev = vk;
    }
  }
  // Uncarried the chain is short by lag x (last velocity - first), 1.7 mm; carried, it is not.
  EXPECT_NEAR(true_sum - measured_sum, lag * 0.1, 1e-15);
  EXPECT_NEAR(carried_sum, true_sum, 1e-15);
}

TEST(DepthClock, LeavesTheMotionWithoutALagAfterAGapAndOnTheFirstPair) {
  const Eigen::Isometry3d M = turn_and_move(0.05, {0.0, 0.0, 0.01});
  DepthClock off(0.0);
  EXPECT_TRUE(off.carry(M, 1.0 / 30, 0.0).isApprox(M, 0));
  EXPECT_TRUE(off.carry(M, 1.0 / 30, 0.013).isApprox(M, 0));  // 0: off, restamped or not
  DepthClock clock(0.02);
  // The first pair: the older frame's velocity is unknown, the pair stays as measured.
  EXPECT_TRUE(clock.carry(M, 1.0 / 30, 0.0).isApprox(M, 0));
  EXPECT_NEAR(clock.frame_shift().translation().z(), 0.02 * 0.3, 1e-12);
  clock.forget();
  EXPECT_TRUE(clock.frame_shift().isApprox(Eigen::Isometry3d::Identity(), 0));
  EXPECT_TRUE(clock.carry(turn_and_move(0.05, {0.0, 0.0, -0.01}), 1.0 / 30, 0.0)
                  .isApprox(turn_and_move(0.05, {0.0, 0.0, -0.01}), 0));
}

TEST(DepthClock, CarriesToThePairsTimesTheLatencyAppliedLess) {
  // Restamped by 13 ms against a gyro, a 17-ms lag leaves 4 ms to carry.
  const double dt = 1.0 / 30;
  DepthClock restamped(0.017), lagging(0.004);
  const Eigen::Isometry3d a = turn_and_move(0.0, {0, 0, 0.002}), b = turn_and_move(0.0, {0, 0, 0.008});
  (void)restamped.carry(a, dt, 0.013);
  (void)lagging.carry(a, dt, 0.0);
  const Eigen::Isometry3d r = restamped.carry(b, dt, 0.013), l = lagging.carry(b, dt, 0.0);
  EXPECT_NEAR(r.translation().z(), l.translation().z(), 1e-15);
  EXPECT_GT(std::abs(r.translation().z() - 0.008), 1e-5);  // it did carry
}

TEST(DepthClock, CarriesTheTiltAlongTheSlideOutOfAChainWhoseTurningRateChanges) {
  // Turning about the image's x axis at a rate held for 6 pairs, then stepped. The tilt is
  // measured at instants `tilt` earlier than the stamps while the image shift (rx - w ty, a point
  // ahead at inverse depth w) is the colour's own, on the stamps: a pair errs along the slide by
  // tilt x the change of rate, in rx and in ty = rx / w. Carried, the chain comes back as between
  // the stamps; every pair keeps its image shift; z and the turn about the optical axis stay.
  const double tilt = 0.007, dt = 1.0 / 30, w = 1 / 1.25;
  const double segments[] = {0.0, 0.6, -0.4, 0.2};  // rad/s
  DepthClock clock(0.0, tilt);
  Eigen::Isometry3d measured_chain = Eigen::Isometry3d::Identity(), carried_chain = measured_chain,
                    true_chain = measured_chain;
  double w_prev = segments[0];
  const auto pair = [&](double angle, double ty) {
    Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
    m.linear() = (Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitX()) * Eigen::AngleAxisd(0.001, Eigen::Vector3d::UnitZ()))
                     .toRotationMatrix();
    m.translation() = Eigen::Vector3d(0.002, ty, 0.004);
    return m;
  };
  const auto rx = [](const Eigen::Isometry3d& m) {
    const Eigen::AngleAxisd turn(m.linear());
    return (turn.angle() * turn.axis()).eval();
  };
  for (double wk : segments) {
    for (int i = 0; i < 6; ++i) {
      const double slide_error = tilt * (wk - w_prev);
      const Eigen::Isometry3d truth = pair(wk * dt, 0.3 * wk * dt);
      const Eigen::Isometry3d m = pair(wk * dt - slide_error, 0.3 * wk * dt - slide_error / w);
      const Eigen::Isometry3d c = clock.carry(m, dt, 0.0, false, w);
      // Kept or left alone to first order: composing the frames' finite shifts (up to 5 mm and
      // 4 mrad) with the pair's turn moves them by up to 0.08 mm and 0.012 mrad, where carrying
      // the tilt alone would move the image shift by up to 7 mrad.
      EXPECT_NEAR(rx(c).x() - w * c.translation().y(), rx(m).x() - w * m.translation().y(), 3e-5);
      EXPECT_NEAR(rx(c).z(), 0.001, 1e-5);
      EXPECT_NEAR(c.translation().z(), 0.004, 1.5e-4);
      if (i >= 4) {  // the step has left the 3 rates averaged: the pair is as between the stamps
        EXPECT_NEAR(rx(c).x(), wk * dt, 1e-5) << wk << " pair " << i;
        EXPECT_NEAR(c.translation().y(), truth.translation().y(), 1.5e-4);
      }
      measured_chain = measured_chain * m;
      carried_chain = carried_chain * c;
      true_chain = true_chain * truth;
      w_prev = wk;
    }
  }
  // Uncarried, the chain's turn errs by tilt x (last rate - first) = 1.4 mrad; carried, by the
  // second-order terms of composing small turns. (Its translation, which the chain's turn mixes
  // with these first-order errors, is checked pair by pair above.)
  EXPECT_NEAR(rx(true_chain).x() - rx(measured_chain).x(), tilt * 0.2, 2e-5);
  EXPECT_NEAR(rx(carried_chain).x(), rx(true_chain).x(), 2e-5);
}

TEST(DepthClock, RetimesTheImageShiftToThePairsTimesByInterpolatingTheChain) {
  // A camera swaying sideways while it turns about the image's y axis. Its pairs' rotations are
  // timed at the pair's times, R before the stamps (as a gyro times them), while their image
  // shift (tx w + ry, a point ahead at inverse depth w) is the colour's own and on the stamps.
  // Retimed by R, each pair's sideways translation comes back as over the pair's times to
  // within the interpolation's third-order error; the rotation is left exactly as measured;
  // and the chain's image shift telescopes to the frames at its ends.
  const double R = 0.014, dt = 1.0 / 30, w = 1 / 1.25;
  const auto x = [](double t) { return 0.1 * std::sin(2 * M_PI * 0.7 * t); };            // m
  const auto yaw = [](double t) { return 0.03 * std::sin(2 * M_PI * 0.45 * t + 1); };    // rad
  const auto motion = [](double tx, double ry) {
    Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
    m.linear() = Eigen::AngleAxisd(ry, Eigen::Vector3d::UnitY()).toRotationMatrix();
    m.translation() = Eigen::Vector3d(tx, 0, 0.001);
    return m;
  };
  DepthClock clock(0.0, 0.0);
  double worst_measured = 0, worst_carried = 0, carried_sum = 0;
  const int pairs = 60;
  for (int k = 1; k <= pairs; ++k) {
    const double a = k * dt - dt, b = k * dt;  // stamps
    const double ry = yaw(b - R) - yaw(a - R);
    const double shift = w * (x(b) - x(a)) + (yaw(b) - yaw(a));
    const Eigen::Isometry3d measured = motion((shift - ry) / w, ry);
    const Eigen::Isometry3d c = clock.carry(measured, dt, R, true, w, R);
    EXPECT_TRUE(c.linear().isApprox(measured.linear(), 1e-15)) << "pair " << k;
    const double truth = x(b - R) - x(a - R);
    if (k == 1) {
      EXPECT_TRUE(c.isApprox(measured, 0)) << "the first pair: the older frame's motion is unknown";
      continue;
    }
    worst_measured = std::max(worst_measured, std::abs(measured.translation().x() - truth));
    worst_carried = std::max(worst_carried, std::abs(c.translation().x() - truth));
    carried_sum += c.translation().x();
  }
  EXPECT_GT(worst_measured, 5e-4);  // R x the change of the image shift's rate: up to 0.9 mm
  EXPECT_LT(worst_carried, worst_measured / 20);
  // Summed from pair 2 on, the measured chain from frame 1 to the last, each end read R earlier
  // by linear interpolation of the measured image shift over its frame's pair (the rest telescopes).
  const auto measured_x = [&](int k) {  // pair k's measured tx and its image shift / w
    const double a = k * dt - dt, b = k * dt;
    const double ry = yaw(b - R) - yaw(a - R), shift = w * (x(b) - x(a)) + (yaw(b) - yaw(a));
    return std::pair<double, double>((shift - ry) / w, shift / w);
  };
  double measured_sum = 0;
  for (int k = 2; k <= pairs; ++k) measured_sum += measured_x(k).first;
  const double alpha = R / dt;
  EXPECT_NEAR(carried_sum, measured_sum - alpha * measured_x(pairs).second + alpha * measured_x(1).second, 2e-6);
  // No depth: nothing can be retimed.
  DepthClock without(0.0, 0.0);
  const Eigen::Isometry3d m = motion(0.01, 0.002);
  (void)without.carry(m, dt, R, true, 0.0, R);
  EXPECT_TRUE(without.carry(m, dt, R, true, 0.0, R).isApprox(m, 0));
}

TEST(DepthClock, CarriesNoTiltWithoutTheInliersDepth) {
  // Without the depth the image shift cannot be kept: the tilt stays as measured.
  DepthClock clock(0.0, 0.007);
  Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
  for (double angle : {0.001, 0.02}) {
    m.linear() = Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitY()).toRotationMatrix();
    EXPECT_TRUE(clock.carry(m, 1.0 / 30, 0.0, false, 0.0).isApprox(m, 1e-15));
  }
}

TEST(DepthClock, WhereAGyroTimesTheRotationsNoTiltIsCarried) {
  // The gyro restamps the pairs at the rotations' own instants: carried as well, a tilt would be
  // moved twice. The optical axis's lag is still carried, less what the restamp applied.
  const double dt = 1.0 / 30;
  const auto turning = [](double angle, double z) {
    Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
    m.linear() = Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitY()).toRotationMatrix();
    m.translation() = Eigen::Vector3d(0, 0, z);
    return m;
  };
  DepthClock timed(0.017, 0.010), untimed(0.017, 0.010), depth_only(0.017, 0.0);
  for (double angle : {0.002, 0.010}) {
    const Eigen::Isometry3d m = turning(angle, 0.01 * angle);
    const Eigen::Isometry3d t = timed.carry(m, dt, 0.013, true, 0.8), d = depth_only.carry(m, dt, 0.013, false, 0.8);
    EXPECT_TRUE(t.isApprox(d, 1e-15));
    (void)untimed.carry(m, dt, 0.013, false, 0.8);
  }
  EXPECT_LT(Eigen::AngleAxisd(timed.frame_shift().linear()).angle(), 1e-15);
  EXPECT_GT(Eigen::AngleAxisd(untimed.frame_shift().linear()).angle(), 1e-4);  // untimed, it is carried
}

}  // namespace
}  // namespace rgbdo
