// The whole pipeline on the bundled real frames (TUM fr1_xyz, first 40), against the
// motion-capture ground truth.
#include <gtest/gtest.h>

#include "rgbd_odometry/io/evaluate.hpp"
#include "rgbd_odometry/pipeline/integrate.hpp"
#include "rgbd_odometry/pipeline/odometry.hpp"
#include "rgbd_odometry/io/tum_sequence.hpp"
#include "rgbd_odometry/core/time_format.hpp"
#include "rgbd_odometry/io/config_file.hpp"

namespace rgbdo {
namespace {

struct Replay {
  std::vector<PairResult> results;
  AccuracySummary summary;
};

Replay replay(const Config& config) {
  const TumSequence seq = open_tum_sequence(RGBDO_TEST_DATA_DIR);
  OdometryPipeline pipeline(config);
  TrajectoryIntegrator integrator;
  AccuracyEvaluator evaluator(seq.groundtruth, allowance_from(estimate_groundtruth_noise(seq.groundtruth.poses())));
  Replay out;
  for (const auto& ref : seq.frames) {
    const auto r = pipeline.process(load_tum_frame(ref, config.depth.units_per_m, 640, 480));
    if (!r) continue;
    if (r->status == Status::Ok) integrator.add(r->T_prev_curr);
    evaluator.add(*r, integrator.pose());
    out.results.push_back(*r);
  }
  out.summary = evaluator.summary();
  return out;
}

const Replay& default_replay() {
  static const Replay r = replay(load_config(RGBDO_CONFIG_DIR "/tum-fr1.yaml"));
  return r;
}

TEST(EndToEnd, EveryPairSucceedsWithASaneCovariance) {
  const auto& r = default_replay();
  ASSERT_EQ(r.results.size(), 39u);
  for (const auto& p : r.results) {
    EXPECT_EQ(p.status, Status::Ok) << format_seconds(p.t_curr_ns);
    EXPECT_GE(p.inliers, 100);
    EXPECT_TRUE(is_valid_covariance(p.covariance));
  }
}

TEST(EndToEnd, AccuracyBeatsThePaperReproduction) {
  // Bounds: the straightforward reproduction of the paper measures 10.6 mm / 0.44 deg RMSE
  // on the full fr1_xyz; this pipeline measures 4.9 mm / 0.30 deg there (README). On these
  // 40 frames it must at least beat the reproduction, with margin left for float and
  // library-version differences.
  const auto& s = default_replay().summary;
  EXPECT_EQ(s.evaluated, 39);
  EXPECT_LT(s.rpe_translation_m.rmse, 0.0080);
  EXPECT_LT(s.rpe_rotation_deg.rmse, 0.40);
  EXPECT_LT(s.drift_translation_mps.rmse, 0.045);
  EXPECT_LT(s.drift_rotation_degps.rmse, 1.6);
}

TEST(EndToEnd, CovarianceIsOfTheRightMagnitudePerAxis) {
  // The default scale makes the per-axis normalised squared errors average ~1 over the full
  // sequence; on any 40-frame stretch they must stay within an order of magnitude.
  const auto& s = default_replay().summary;
  EXPECT_GT(s.axis_nees.mean(), 0.1);
  EXPECT_LT(s.axis_nees.mean(), 10.0);
}

TEST(EndToEnd, TimingCompensationImprovesTranslation) {
  Config c = load_config(RGBDO_CONFIG_DIR "/tum-fr1.yaml");
  c.depth.compensate_timing = false;
  const auto naive = replay(c).summary;
  EXPECT_LT(default_replay().summary.rpe_translation_m.rmse, naive.rpe_translation_m.rmse);
}

TEST(EndToEnd, SameSeedReplaysExactly) {
  const auto again = replay(load_config(RGBDO_CONFIG_DIR "/tum-fr1.yaml"));
  const auto& first = default_replay();
  for (size_t i = 0; i < first.results.size(); ++i) {
    EXPECT_TRUE(first.results[i].T_prev_curr.isApprox(again.results[i].T_prev_curr, 0));
    EXPECT_EQ(first.results[i].covariance, again.results[i].covariance);
  }
}

TEST(EndToEnd, MotionWindowMatchesAsWellAsTheFullSearch) {
  // Matching within matching.window_px of where the last velocity puts each keypoint (the
  // default) against the paper's search over all pairs: on real hand-held motion no pair
  // needs the full search again, and the accuracy is the full search's (measured on these
  // frames: 4.384 against 4.383 mm, 0.307 against 0.307 deg).
  const auto& windowed = default_replay();
  Config c = load_config(RGBDO_CONFIG_DIR "/tum-fr1.yaml");
  ASSERT_GT(c.matching.window_px, 0);
  c.matching.window_px = 0;
  const auto full = replay(c);
  int rematched = 0;
  for (const auto& p : windowed.results) rematched += p.rematched ? 1 : 0;
  EXPECT_EQ(rematched, 0);
  for (const auto& p : full.results) EXPECT_FALSE(p.rematched);
  EXPECT_LT(windowed.summary.rpe_translation_m.rmse, 1.04 * full.summary.rpe_translation_m.rmse);
  EXPECT_LT(windowed.summary.rpe_rotation_deg.rmse, 1.05 * full.summary.rpe_rotation_deg.rmse);
}

TEST(EndToEnd, APairTheWindowMissesIsMatchedAgainOverTheWholeImage) {
  // Frames 0.6 s apart with no velocity yet (the first pair): a 2-pixel window finds almost
  // nothing, so the pair is matched again over all pairs and solved exactly as the full
  // search solves it (the same random streams).
  const TumSequence seq = open_tum_sequence(RGBDO_TEST_DATA_DIR);
  const auto solve = [&](double window_px) {
    Config c = load_config(RGBDO_CONFIG_DIR "/tum-fr1.yaml");
    c.matching.window_px = window_px;
    OdometryPipeline pipeline(c);
    EXPECT_FALSE(pipeline.process(load_tum_frame(seq.frames[0], 5000, 640, 480)));
    return *pipeline.process(load_tum_frame(seq.frames[18], 5000, 640, 480));
  };
  const PairResult narrow = solve(2), full = solve(0);
  ASSERT_EQ(full.status, Status::Ok);
  EXPECT_TRUE(narrow.rematched);
  EXPECT_FALSE(full.rematched);
  EXPECT_EQ(narrow.status, Status::Ok);
  EXPECT_EQ(narrow.matches, full.matches);
  EXPECT_EQ(narrow.inliers, full.inliers);
  EXPECT_TRUE(narrow.T_prev_curr.isApprox(full.T_prev_curr, 0));
  EXPECT_EQ(narrow.covariance, full.covariance);
}

TEST(EndToEnd, TexturelessAndDepthlessFramesFailCleanlyAndTrackingResumes) {
  const Config config = load_config(RGBDO_CONFIG_DIR "/tum-fr1.yaml");
  const TumSequence seq = open_tum_sequence(RGBDO_TEST_DATA_DIR);
  OdometryPipeline pipeline(config);
  const auto real = [&](size_t i) { return load_tum_frame(seq.frames[i], 5000, 640, 480); };
  RgbdFrame blank = real(1);
  blank.gray.setTo(128);  // a blank wall: depth but no texture
  RgbdFrame no_depth = real(2);
  no_depth.depth_m.setTo(0);  // sensor delivered an empty depth image
  RgbdFrame missing = real(3);
  missing.status = Status::BadFrame;
  EXPECT_FALSE(pipeline.process(real(0)));
  EXPECT_EQ(pipeline.process(blank)->status, Status::TooFewFeatures);
  EXPECT_EQ(pipeline.process(no_depth)->status, Status::NoDepth);
  EXPECT_EQ(pipeline.process(missing)->status, Status::BadFrame);
  EXPECT_EQ(pipeline.process(real(4))->status, Status::BadFrame);  // its predecessor is bad
  const auto resumed = pipeline.process(real(5));
  EXPECT_EQ(resumed->status, Status::Ok);
  EXPECT_TRUE(is_valid_covariance(resumed->covariance));
}

}  // namespace
}  // namespace rgbdo
