// Our own extractor (pipeline/grid_orb.hpp) on real frames and on images with known answers:
// budget and mask kept, keypoints spread over the image (more grid cells covered than
// OpenCV's ORB covers with the same budget), orientation from the intensity centroid, each
// descriptor bit the comparison its definition states, and rotation invariance.
#include <gtest/gtest.h>

#include <bitset>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <set>

#include "rgbd_odometry/app/config_file.hpp"
#include "rgbd_odometry/io/tum_sequence.hpp"
#include "rgbd_odometry/pipeline/detect.hpp"
#include "rgbd_odometry/pipeline/grid_orb.hpp"
#include "rgbd_odometry/pipeline/mask.hpp"

namespace rgbdo {
namespace {

struct Frame {
  cv::Mat gray, mask;
};

Frame bundled_frame(int index) {
  const Config config = load_config(RGBDO_CONFIG_DIR "/tum-fr1.yaml");
  const TumSequence seq = open_tum_sequence(RGBDO_TEST_DATA_DIR);
  const RgbdFrame f = load_tum_frame(seq.frames[static_cast<size_t>(index)], config.depth.units_per_m, 640, 480);
  Frame out{f.gray, {}};
  build_feature_mask(f.depth_m, config.depth, config.features.border_px, out.mask);
  return out;
}

FeatureConfig grid_orb_config() {
  FeatureConfig c = load_config(RGBDO_CONFIG_DIR "/tum-fr1.yaml").features;
  c.detector = c.descriptor = "GRID_ORB";
  return c;
}

// Grid cells of 40 x 40 level-0 pixels holding at least one keypoint.
size_t occupied_cells(const std::vector<cv::KeyPoint>& keypoints) {
  std::set<int> cells;
  for (const auto& k : keypoints) cells.insert(static_cast<int>(k.pt.y) / 40 * 100 + static_cast<int>(k.pt.x) / 40);
  return cells.size();
}

TEST(GridOrb, KeepsTheBudgetAndTheMaskAndSpreadsTheKeypoints) {
  const Frame f = bundled_frame(0);
  const FeatureConfig config = grid_orb_config();
  GridOrbExtractor extractor(config, 640, 480);
  Features ours;
  extractor.detect(f.gray, f.mask, ours);
  // A textured frame fills the budget; every keypoint lies where the mask allows.
  EXPECT_EQ(ours.keypoints.size(), static_cast<size_t>(config.max_features));
  EXPECT_EQ(ours.descriptors.rows, static_cast<int>(ours.keypoints.size()));
  EXPECT_EQ(ours.descriptors.cols, 32);
  for (const auto& k : ours.keypoints) {
    ASSERT_NE(f.mask.at<std::uint8_t>(static_cast<int>(k.pt.y + 0.5f), static_cast<int>(k.pt.x + 0.5f)), 0)
        << k.pt << " level " << k.octave;
  }
  // Every level contributes, the finest most (ORB-SLAM's geometric budget).
  std::vector<int> per_level(static_cast<size_t>(config.orb_levels), 0);
  for (const auto& k : ours.keypoints) ++per_level[static_cast<size_t>(k.octave)];
  for (int l = 0; l < config.orb_levels; ++l) EXPECT_GT(per_level[static_cast<size_t>(l)], 0) << "level " << l;
  EXPECT_GT(per_level[0], per_level[static_cast<size_t>(config.orb_levels - 1)]);
  // Spread: OpenCV's ORB with the same budget, pyramid and threshold covers fewer cells (it
  // keeps the strongest corners wherever they clump).
  cv::Ptr<cv::ORB> orb = cv::ORB::create(config.max_features, static_cast<float>(config.orb_scale_factor),
                                         config.orb_levels, 31, 0, 2, cv::ORB::HARRIS_SCORE, 31, config.fast_threshold);
  std::vector<cv::KeyPoint> theirs;
  orb->detect(f.gray, theirs, f.mask);
  const size_t ours_cells = occupied_cells(ours.keypoints), theirs_cells = occupied_cells(theirs);
  std::printf("40-px cells covered: GRID_ORB %zu, OpenCV ORB %zu (of %zu keypoints each)\n", ours_cells, theirs_cells,
              ours.keypoints.size());
  EXPECT_GT(ours_cells, theirs_cells + theirs_cells / 10);
}

TEST(GridOrb, ATexturelessCellStillYieldsItsBestCornerAtTheLowThreshold) {
  // A flat image with one faint corner (contrast 12: below fast_threshold 20, above 7).
  cv::Mat gray(240, 320, CV_8UC1, cv::Scalar(100));
  cv::rectangle(gray, cv::Rect(160, 120, 40, 40), cv::Scalar(112), cv::FILLED);
  const cv::Mat mask(gray.size(), CV_8UC1, cv::Scalar(255));
  FeatureConfig config = grid_orb_config();
  config.orb_levels = 1;
  GridOrbExtractor extractor(config, 320, 240);
  Features out;
  extractor.detect(gray, mask, out);
  ASSERT_FALSE(out.keypoints.empty());
  bool at_corner = false;
  for (const auto& k : out.keypoints) at_corner |= std::abs(k.pt.x - 160) <= 2 && std::abs(k.pt.y - 120) <= 2;
  EXPECT_TRUE(at_corner);
  // At the full threshold alone nothing would be found: check with OpenCV's FAST.
  std::vector<cv::KeyPoint> fast;
  cv::FAST(gray, fast, config.fast_threshold, true);
  EXPECT_TRUE(fast.empty());
}

TEST(GridOrb, OrientationPointsToTheBrightSide) {
  // A corner whose bright quadrant lies towards +x (right) and then towards +y (down).
  for (const cv::Rect quadrant : {cv::Rect(160, 100, 60, 40), cv::Rect(140, 120, 40, 60)}) {
    cv::Mat gray(240, 320, CV_8UC1, cv::Scalar(40));
    cv::rectangle(gray, quadrant, cv::Scalar(220), cv::FILLED);
    FeatureConfig config = grid_orb_config();
    config.orb_levels = 1;
    GridOrbExtractor extractor(config, 320, 240);
    Features out;
    extractor.detect(gray, cv::Mat(gray.size(), CV_8UC1, cv::Scalar(255)), out);
    ASSERT_FALSE(out.keypoints.empty());
    // The strongest corner is a corner of the bright rectangle; the centroid lies inside it.
    const auto best = *std::max_element(out.keypoints.begin(), out.keypoints.end(),
                                        [](const auto& a, const auto& b) { return a.response < b.response; });
    const cv::Point2f centre(quadrant.x + quadrant.width / 2.0f, quadrant.y + quadrant.height / 2.0f);
    const float to_centre = std::atan2(centre.y - best.pt.y, centre.x - best.pt.x) * 180.0f / static_cast<float>(M_PI);
    float diff = std::fmod(std::abs(best.angle - to_centre), 360.0f);
    diff = std::min(diff, 360.0f - diff);
    EXPECT_LE(diff, 30.0f) << "keypoint " << best.pt << " angle " << best.angle << " centre at " << to_centre;
  }
}

TEST(GridOrb, EachBitIsTheComparisonOfTwoBoxMeansOfThePattern) {
  // The definition, computed directly: at angle 0 (a keypoint on level 0 whose centroid lies
  // straight to the right), bit i is box5(p1_i) < box5(p2_i) on the unsmoothed image.
  cv::Mat gray(200, 200, CV_8UC1);
  cv::randu(gray, 0, 60);
  cv::rectangle(gray, cv::Rect(100, 80, 60, 41), cv::Scalar(250), cv::FILLED);  // corners, bright to the right
  FeatureConfig config = grid_orb_config();
  config.orb_levels = 1;
  GridOrbExtractor extractor(config, 200, 200);
  Features out;
  extractor.detect(gray, cv::Mat(gray.size(), CV_8UC1, cv::Scalar(255)), out);
  int checked = 0;
  for (size_t k = 0; k < out.keypoints.size(); ++k) {
    const cv::KeyPoint& kp = out.keypoints[k];
    if (kp.angle != 0.0f) continue;
    const int x = static_cast<int>(std::lround(kp.pt.x)), y = static_cast<int>(std::lround(kp.pt.y));
    const auto box = [&](int dx, int dy) {
      int sum = 0;
      for (int v = -2; v <= 2; ++v)
        for (int u = -2; u <= 2; ++u) sum += gray.at<std::uint8_t>(y + dy + v, x + dx + u);
      return sum;
    };
    const auto& pattern = GridOrbExtractor::pattern();
    for (int i = 0; i < 256; ++i) {
      const auto& p = pattern[static_cast<size_t>(i)];
      const bool bit = (out.descriptors.at<std::uint8_t>(static_cast<int>(k), i / 8) >> (i % 8)) & 1;
      ASSERT_EQ(bit, box(p.x1, p.y1) < box(p.x2, p.y2)) << "keypoint " << kp.pt << " bit " << i;
    }
    ++checked;
  }
  EXPECT_GT(checked, 0) << "no keypoint at angle 0 to check";
}

TEST(GridOrb, ThePatternIsFixedCentredAndWithinTheSteeringDisc) {
  const auto& p = GridOrbExtractor::pattern();
  double mean_x = 0, mean_y = 0, var = 0;
  for (const auto& q : p) {
    for (const auto& [x, y] : {std::pair{q.x1, q.y1}, std::pair{q.x2, q.y2}}) {
      EXPECT_LE(x * x + y * y, 13 * 13);
      mean_x += x;
      mean_y += y;
      var += x * x + y * y;
    }
    EXPECT_FALSE(q.x1 == q.x2 && q.y1 == q.y2);
  }
  mean_x /= 512;
  mean_y /= 512;
  var /= 1024;  // per coordinate
  // BRIEF G II: sigma 31/5 = 6.2 per coordinate, clipped to the disc of radius R = 13: per
  // coordinate E[r^2 | r <= R] / 2 = sigma^2 (1 - a e^-a / (1 - e^-a)), a = R^2 / (2 sigma^2),
  // i.e. a standard deviation of 5.28 (sampling error of 1024 coordinates: ~0.12).
  EXPECT_NEAR(mean_x, 0, 0.6);
  EXPECT_NEAR(mean_y, 0, 0.6);
  EXPECT_NEAR(std::sqrt(var), 5.28, 0.3);
  // Fixed: the same pattern in every build (its first pairs, as drawn from the seed).
  EXPECT_EQ(&p, &GridOrbExtractor::pattern());
}

TEST(GridOrb, DescriptorsSurviveAQuarterTurn) {
  // The same frame turned by 90 degrees (an exact pixel permutation): the steered descriptors
  // of keypoints found at corresponding places are close (steering in 12-degree steps).
  const Frame f = bundled_frame(0);
  cv::Mat turned_gray, turned_mask;
  cv::rotate(f.gray, turned_gray, cv::ROTATE_90_CLOCKWISE);
  cv::rotate(f.mask, turned_mask, cv::ROTATE_90_CLOCKWISE);
  const FeatureConfig config = grid_orb_config();
  GridOrbExtractor upright(config, 640, 480), turned(config, 480, 640);
  Features a, b;
  upright.detect(f.gray, f.mask, a);
  turned.detect(turned_gray, turned_mask, b);
  // Rotating clockwise maps (x, y) to (h - 1 - y, x).
  int pairs = 0, close = 0;
  for (size_t i = 0; i < a.keypoints.size(); ++i) {
    if (a.keypoints[i].octave != 0) continue;
    const cv::Point2f expected(479.0f - a.keypoints[i].pt.y, a.keypoints[i].pt.x);
    for (size_t j = 0; j < b.keypoints.size(); ++j) {
      if (b.keypoints[j].octave != 0 || cv::norm(b.keypoints[j].pt - expected) > 0.5) continue;
      ++pairs;
      const int d = cv::norm(a.descriptors.row(static_cast<int>(i)), b.descriptors.row(static_cast<int>(j)), cv::NORM_HAMMING);
      close += d <= 40;  // of 256 bits; unrelated descriptors differ in ~128
    }
  }
  ASSERT_GT(pairs, 50);
  EXPECT_GT(close, pairs * 8 / 10) << close << " of " << pairs;
}

TEST(GridOrb, SelectedByNameThroughTheFeatureDetector) {
  const Frame f = bundled_frame(3);
  FeatureDetector detector(grid_orb_config());
  Features out;
  detector.detect(f.gray, f.mask, out);
  EXPECT_TRUE(detector.binary_descriptors());
  EXPECT_EQ(out.keypoints.size(), 1000u);
  EXPECT_EQ(out.descriptors.type(), CV_8UC1);
}

TEST(FeatureDetector, EveryDetectorKeepsToMaxFeatures) {
  // OpenCV's FAST finds ~2,700 corners on a textured frame and knows no cap: the strongest
  // max_features are kept (matching's cost is bounded by the configuration), descriptors
  // for exactly those.
  const Frame f = bundled_frame(0);
  for (const auto& [detector, descriptor] : {std::pair{"FAST", "ORB"}, std::pair{"AGAST", "BRISK"}, std::pair{"AKAZE", "AKAZE"}}) {
    FeatureConfig config = grid_orb_config();
    config.detector = detector;
    config.descriptor = descriptor;
    config.max_features = 300;
    FeatureDetector d(config);
    Features out;
    d.detect(f.gray, f.mask, out);
    // A textured frame has far more; the descriptor may then drop a few near the border
    // (ORB's does: 289 of FAST's 300 kept on this frame).
    EXPECT_LE(out.keypoints.size(), 300u) << detector;
    EXPECT_GE(out.keypoints.size(), 280u) << detector;
    EXPECT_EQ(out.descriptors.rows, static_cast<int>(out.keypoints.size())) << detector;
  }
}

}  // namespace
}  // namespace rgbdo
