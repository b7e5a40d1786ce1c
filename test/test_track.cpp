// The sub-pixel tracker: its kernels against the scalar reference (every compiled set the CPU
// runs) and against a bilinear sample worked by hand; the tracker against known sub-pixel
// shifts of a real frame, and its refusals (no texture, a bound exceeded, the image border).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "rgbd_odometry/core/rng.hpp"
#include "rgbd_odometry/app/config_file.hpp"
#include "rgbd_odometry/io/tum_sequence.hpp"
#include "rgbd_odometry/pipeline/backproject.hpp"
#include "rgbd_odometry/pipeline/track.hpp"
#include "rgbd_odometry/simd/kernels.hpp"
#include "runnable_kernel_sets.hpp"

namespace rgbdo {
namespace {

// Four weights summing to 2^14, as the tracker makes them.
std::array<std::int32_t, 4> random_weights(Rng& rng) {
  const int one = 1 << simd::kTrackWeightBits;
  const auto a = static_cast<std::int32_t>(rng.uniform01() * one), b = static_cast<std::int32_t>(rng.uniform01() * (one - a));
  const auto c = static_cast<std::int32_t>(rng.uniform01() * (one - a - b));
  return {a, b, c, one - a - b - c};
}

TEST(TrackKernels, TwinsAreBitExactOverRandomImagesWeightsAndPatches) {
  Rng rng(7);
  cv::Mat image(40, 40, CV_8UC1);
  for (int y = 0; y < image.rows; ++y)
    for (int x = 0; x < image.cols; ++x) image.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(rng.uniform01() * 256);
  // The extremes: all 255 under the largest single weight, where a wrong rounding or lane
  // width shows first.
  image(cv::Rect(20, 20, 12, 12)).setTo(255);
  const auto sets = twins_of_reference(&simd::KernelSet::track_sample8);
  for (int trial = 0; trial < 2000; ++trial) {
    const auto w = trial == 0 ? std::array<std::int32_t, 4>{1 << simd::kTrackWeightBits, 0, 0, 0} : random_weights(rng);
    const int x = trial == 0 ? 20 : static_cast<int>(rng.uniform01() * 28), y = trial == 0 ? 20 : static_cast<int>(rng.uniform01() * 28);
    const int rows = trial % 2 == 0 ? 8 : 10;
    std::array<std::int16_t, 80> expected{}, got{};
    expected.fill(-1);  // what lies past the rows must stay untouched
    simd::track_sample8_scalar(image.ptr<std::uint8_t>(y) + x, static_cast<std::ptrdiff_t>(image.step), rows, w.data(),
                               expected.data());
    for (const auto* set : sets) {
      got.fill(-1);
      set->track_sample8(image.ptr<std::uint8_t>(y) + x, static_cast<std::ptrdiff_t>(image.step), rows, w.data(),
                         got.data());
      ASSERT_EQ(got, expected) << set->name << ", trial " << trial;
    }
    // The sums over the sample against another sample as template, with its own gradients.
    std::array<std::int16_t, 64> templ{}, gx{}, gy{};
    for (int k = 0; k < 64; ++k) {
      templ[static_cast<size_t>(k)] = static_cast<std::int16_t>(rng.uniform01() * 2041);
      gx[static_cast<size_t>(k)] = static_cast<std::int16_t>(rng.uniform01() * 4081 - 2040);
      gy[static_cast<size_t>(k)] = static_cast<std::int16_t>(rng.uniform01() * 4081 - 2040);
    }
    std::array<std::int32_t, 3> sums_expected{}, sums{};
    simd::track_sums8x8_scalar(expected.data(), templ.data(), gx.data(), gy.data(), sums_expected.data());
    for (const auto* set : twins_of_reference(&simd::KernelSet::track_sums8x8)) {
      set->track_sums8x8(expected.data(), templ.data(), gx.data(), gy.data(), sums.data());
      ASSERT_EQ(sums, sums_expected) << set->name << ", trial " << trial;
    }
  }
}

TEST(TrackKernels, TheSampleIsTheBilinearMeanInEighthsOfAGreyLevel) {
  // Pixels 10 | 20 over 30 | 40; the point a quarter of the way right and half way down:
  // 0.375 * 10 + 0.125 * 20 + 0.375 * 30 + 0.125 * 40 = 22.5 grey levels = 180 eighths.
  cv::Mat image(10, 16, CV_8UC1, cv::Scalar(0));
  image.at<std::uint8_t>(0, 0) = 10;
  image.at<std::uint8_t>(0, 1) = 20;
  image.at<std::uint8_t>(1, 0) = 30;
  image.at<std::uint8_t>(1, 1) = 40;
  const std::array<std::int32_t, 4> w{6144, 2048, 6144, 2048};  // (0.375, 0.125, 0.375, 0.125) x 2^14
  for (const auto* set : sets_with_own(&simd::KernelSet::track_sample8)) {
    std::array<std::int16_t, 64> out{};
    set->track_sample8(image.data, static_cast<std::ptrdiff_t>(image.step), 8, w.data(), out.data());
    EXPECT_EQ(out[0], 180) << set->name;
    EXPECT_EQ(out[1], 180) << set->name;  // 0.375 * 20 + 0.375 * 40, the black pixels to its right
    EXPECT_EQ(out[2], 0) << set->name;
  }
  // The sums of a patch one eighth of a grey level above its template, gradients 1 and -2.
  std::array<std::int16_t, 64> sampled{}, templ{}, gx{}, gy{};
  sampled.fill(101);
  templ.fill(100);
  gx.fill(1);
  gy.fill(-2);
  for (const auto* set : sets_with_own(&simd::KernelSet::track_sums8x8)) {
    std::array<std::int32_t, 3> sums{};
    set->track_sums8x8(sampled.data(), templ.data(), gx.data(), gy.data(), sums.data());
    EXPECT_EQ(sums, (std::array<std::int32_t, 3>{64, -128, 64})) << set->name;
  }
}

cv::Mat bundled_gray(int index) {
  const Config config = load_config(RGBDO_CONFIG_DIR "/tum-fr1.yaml");
  const TumSequence seq = open_tum_sequence(RGBDO_TEST_DATA_DIR);
  return load_tum_frame(seq.frames[static_cast<size_t>(index)], config.depth.units_per_m, 640, 480).gray;
}

// `image` moved by (dx, dy) pixels: what was at p is at p + (dx, dy). Bicubic, so that the
// tracker's own bilinear sampling is not the law the shift was made with.
cv::Mat shifted(const cv::Mat& image, double dx, double dy) {
  const cv::Mat m = (cv::Mat_<double>(2, 3) << 1, 0, dx, 0, 1, dy);
  cv::Mat out;
  cv::warpAffine(image, out, m, image.size(), cv::INTER_CUBIC, cv::BORDER_REPLICATE);
  return out;
}

std::vector<cv::Point2f> corners_of(const cv::Mat& gray) {
  std::vector<cv::Point2f> corners;
  cv::goodFeaturesToTrack(gray, corners, 300, 0.01, 10, cv::noArray(), 3, false);
  return corners;
}

SubpixelTracker tracker_for_fr1() {
  const Config config = load_config(RGBDO_CONFIG_DIR "/tum-fr1.yaml");
  return SubpixelTracker(config.camera, config.features.orb_scale_factor, config.features.max_features);
}

TEST(SubpixelTracker, FindsAKnownSubpixelShiftOfARealFrame) {
  const cv::Mat prev = bundled_gray(0);
  const SubpixelTracker tracker = tracker_for_fr1();
  for (const auto& [dx, dy] : {std::pair{0.3, -0.45}, std::pair{-0.7, 0.2}, std::pair{0.5, 0.5}}) {
    const cv::Mat curr = shifted(prev, dx, dy);
    std::vector<double> errors, start_errors;
    for (const auto& c : corners_of(prev)) {
      const Eigen::Vector2d from(c.x, c.y), truth(c.x + dx, c.y + dy);
      // Started where an integer-grid detector would put the corner in the shifted image.
      const Eigen::Vector2d start(std::round(truth.x()), std::round(truth.y()));
      const PatchTrack t = tracker.track_patch(prev, from, curr, start, 1.0);
      if (!t.ok) continue;
      errors.push_back((t.position - truth).norm());
      start_errors.push_back((start - truth).norm());
    }
    ASSERT_GE(errors.size(), 250u) << "most corners of a real frame track";
    std::sort(errors.begin(), errors.end());
    std::sort(start_errors.begin(), start_errors.end());
    const double median = errors[errors.size() / 2], p90 = errors[errors.size() * 9 / 10];
    // Measured: medians 0.034-0.044 px, 90th percentiles 0.063-0.102 px (the bilinear
    // sampling's own blur differs with the fraction of a pixel), against the integer grid's
    // 0.36-0.71 px.
    EXPECT_LT(median, 0.055) << dx << ", " << dy;
    EXPECT_LT(p90, 0.125) << dx << ", " << dy;
    EXPECT_GT(start_errors[start_errors.size() / 2], 7 * median);
  }
}

TEST(SubpixelTracker, RefusesPatchesWithoutTextureInBothDirections) {
  const SubpixelTracker tracker = tracker_for_fr1();
  cv::Mat flat(60, 60, CV_8UC1, cv::Scalar(128));
  EXPECT_FALSE(tracker.track_patch(flat, {30, 30}, flat, {30, 30}, 1.0).ok);
  // A straight vertical edge: a shift along it cannot be seen.
  cv::Mat edge = flat.clone();
  edge(cv::Rect(30, 0, 30, 60)).setTo(200);
  EXPECT_FALSE(tracker.track_patch(edge, {30.2, 30}, edge, {30, 30}, 1.0).ok);
  // The same edge with a corner in it tracks.
  cv::Mat corner = flat.clone();
  corner(cv::Rect(30, 30, 30, 30)).setTo(200);
  cv::GaussianBlur(corner, corner, cv::Size(5, 5), 1.0);
  EXPECT_TRUE(tracker.track_patch(corner, {30.2, 30.1}, corner, {30, 30}, 1.0).ok);
}

TEST(SubpixelTracker, RefusesATrackBeyondItsBoundOrTheImage) {
  const cv::Mat prev = bundled_gray(0);
  const cv::Mat curr = shifted(prev, 2.6, 0.0);
  const SubpixelTracker tracker = tracker_for_fr1();
  const auto corners = corners_of(prev);
  int within_1px = 0, within_4px = 0, right = 0;
  for (const auto& c : corners) {
    const Eigen::Vector2d from(c.x, c.y), start(c.x, c.y), truth(c.x + 2.6, c.y);
    within_1px += tracker.track_patch(prev, from, curr, start, 1.0).ok;
    const PatchTrack far = tracker.track_patch(prev, from, curr, start, 4.0);
    within_4px += far.ok;
    right += far.ok && (far.position - truth).norm() < 0.05;
  }
  // 2.6 px is further than a bound of 1 allows: none may end there.
  EXPECT_EQ(within_1px, 0);
  EXPECT_GT(within_4px, static_cast<int>(corners.size()) * 8 / 10);
  EXPECT_GT(right, within_4px * 9 / 10);
  // Patches reaching past the image's edge are refused, on either image.
  EXPECT_FALSE(tracker.track_patch(prev, {3.0, 100.0}, curr, {3.0, 100.0}, 1.0).ok);
  EXPECT_FALSE(tracker.track_patch(prev, {320.0, 476.5}, curr, {320.0, 476.5}, 1.0).ok);
  EXPECT_FALSE(tracker.track_patch(prev, {100.0, 100.0}, curr, {636.0, 100.0}, 1.0).ok);
}

TEST(SubpixelTracker, MovesTheMatchedKeypointsRayAndDepthWithIt) {
  const Config config = load_config(RGBDO_CONFIG_DIR "/tum-fr1.yaml");
  const TumSequence seq = open_tum_sequence(RGBDO_TEST_DATA_DIR);
  const RgbdFrame f = load_tum_frame(seq.frames[0], config.depth.units_per_m, 640, 480);
  const cv::Mat curr_gray = shifted(f.gray, 0.4, -0.3);
  // Keypoints at corners of the frame, the same positions in both frames: the tracker must
  // move each current one by the shift.
  std::vector<cv::KeyPoint> keypoints;
  for (const auto& c : corners_of(f.gray)) keypoints.emplace_back(c, 7.f, -1.f, 0.f, 0);
  KeypointBackProjector backprojector(config.camera, config.depth);
  KeypointGeometry geometry;
  backprojector.compute(keypoints, f.depth_m, geometry);
  std::vector<Match> matches;
  std::vector<int> which;
  for (size_t k = 0; k < keypoints.size(); ++k) {
    matches.push_back({static_cast<int>(k), static_cast<int>(k), 0.f});
    if (k % 2 == 0) which.push_back(static_cast<int>(k));  // every other match is tracked
  }
  SubpixelTracker tracker = tracker_for_fr1();
  KeypointGeometry out;
  const int moved = tracker.track(f.gray, geometry, curr_gray, geometry, keypoints, matches, which, out);
  EXPECT_GT(moved, static_cast<int>(which.size()) * 8 / 10);
  ASSERT_EQ(out.pixel.size(), geometry.pixel.size());
  int checked = 0;
  std::vector<double> shift_errors;
  for (size_t k = 0; k < keypoints.size(); ++k) {
    const Eigen::Vector2d shift = out.pixel[k] - geometry.pixel[k];
    if (k % 2 == 1 || shift.norm() == 0) {
      // Not tracked (or refused): as detected.
      EXPECT_EQ(out.pixel[k], geometry.pixel[k]);
      EXPECT_EQ(out.normalized[k], geometry.normalized[k]);
      EXPECT_EQ(out.depth_m[k], geometry.depth_m[k]);
      continue;
    }
    ++checked;
    shift_errors.push_back((shift - Eigen::Vector2d(0.4, -0.3)).norm());
    // Its ray: the undistorted position of its new pixel, as the back-projector computes it.
    KeypointGeometry one;
    backprojector.compute({cv::KeyPoint(cv::Point2f(static_cast<float>(out.pixel[k].x()), static_cast<float>(out.pixel[k].y())), 7.f)},
                          f.depth_m, one);
    EXPECT_NEAR((out.normalized[k] - one.normalized[0]).norm(), 0, 1e-6);
    // Its depth: along the slope read at the keypoint.
    if (geometry.depth_m[k] > 0) {
      EXPECT_DOUBLE_EQ(out.depth_m[k], geometry.depth_m[k] + geometry.depth_gradient[k].dot(shift));
    }
  }
  EXPECT_GT(checked, 50);
  std::sort(shift_errors.begin(), shift_errors.end());
  ASSERT_FALSE(shift_errors.empty());
  EXPECT_LT(shift_errors[shift_errors.size() / 2], 0.055);  // as the test above
}

}  // namespace
}  // namespace rgbdo
