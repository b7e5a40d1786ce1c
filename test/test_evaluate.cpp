// The evaluation against ground truth on synthetic data with known noise: the ground truth's
// own jitter recovered from its file, and the consistency figures (NEES per pair and over 1-s
// windows, per axis over windows, lag-1 correlation) for errors independent, persistent and
// shared between pairs, and the streams' time offsets recovered from lagged motions.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

#include "rgbd_odometry/core/rng.hpp"
#include "rgbd_odometry/eval/evaluate.hpp"
#include "rgbd_odometry/eval/groundtruth_noise.hpp"

namespace rgbdo {
namespace {

constexpr std::int64_t kSecond = 1'000'000'000;

Eigen::Isometry3d true_pose(double t) {
  Vector6d xi;
  xi << 0.3 * std::sin(0.5 * t), 0.2 * std::sin(0.7 * t + 1), 0.1 * t, 0.2 * std::sin(0.3 * t),
      0.3 * std::sin(0.4 * t), 0.1 * t;
  return transform_from_xi(xi);
}

// A hand-held camera's back-and-forth: 1-2 Hz swings, as in TUM's fr1_xyz.
Eigen::Isometry3d swinging_pose(double t) {
  Vector6d xi;
  xi << 0.1 * std::sin(6 * t), 0.05 * std::sin(9 * t + 1), 0.1 * std::sin(7 * t + 2), 0.05 * std::sin(8 * t),
      0.06 * std::sin(5 * t + 1), 0.03 * std::sin(11 * t);
  return transform_from_xi(xi);
}

// 100 Hz motion capture for `seconds`, each sample off by the given jitter.
GroundTruth motion_capture(double seconds, double position_sigma_m, double rotation_sigma_rad, std::uint64_t seed,
                           const std::function<Eigen::Isometry3d(double)>& pose_at = true_pose) {
  Rng rng(seed);
  std::vector<StampedPose> poses;
  for (int i = 0; i < static_cast<int>(seconds * 100); ++i) {
    Eigen::Isometry3d T = pose_at(i * 0.01);
    T.translation() += position_sigma_m * Eigen::Vector3d(rng.gaussian(), rng.gaussian(), rng.gaussian());
    T.linear() = T.linear() * rotation_from_vector(rotation_sigma_rad *
                                                  Eigen::Vector3d(rng.gaussian(), rng.gaussian(), rng.gaussian()));
    poses.push_back({static_cast<std::int64_t>(i) * kSecond / 100, T});
  }
  return GroundTruth(std::move(poses));
}

TEST(GroundTruthNoise, RecoversTheJitterOfTheSamples) {
  const GroundTruth gt = motion_capture(60, 0.00015, 0.001, 1);
  const GroundTruthNoise n = estimate_groundtruth_noise(gt.poses());
  EXPECT_GT(n.samples, 5900);
  // 3 x 5994 residuals: the median-based estimate scatters by ~2 %; the motion's own
  // curvature over 70 ms adds well under 1 %.
  EXPECT_NEAR(n.position_m, 0.00015, 0.05 * 0.00015);  // measured 0.1487 mm
  EXPECT_NEAR(n.rotation_rad, 0.001, 0.05 * 0.001);    // measured 0.992 mrad
  const GroundTruthAllowance a = allowance_from(n);
  EXPECT_NEAR(a.translation_m, std::sqrt(2.0) * n.position_m, 1e-15);
}

TEST(GroundTruthNoise, ASmoothNoiselessTrajectoryHasNone) {
  const GroundTruthNoise n = estimate_groundtruth_noise(motion_capture(20, 0, 0, 1).poses());
  EXPECT_LT(n.position_m, 1e-6);
  EXPECT_LT(n.rotation_rad, 1e-5);
}

TEST(GroundTruthAllowanceText, ParsesAndRefuses) {
  const GroundTruth gt = motion_capture(5, 0.0001, 0.001, 2);
  const GroundTruthAllowance a = parse_allowance("0.0003,0.0015", gt);
  EXPECT_DOUBLE_EQ(a.translation_m, 0.0003);
  EXPECT_DOUBLE_EQ(a.rotation_rad, 0.0015);
  EXPECT_EQ(parse_allowance("none", gt).translation_m, 0.0);
  EXPECT_GT(parse_allowance("auto", gt).translation_m, 0.0);
  for (const char* bad : {"", "0.1", "a,b", "0.1,-1", "0.1,0.2x", "nan,1"})
    EXPECT_THROW(parse_allowance(bad, gt), std::invalid_argument) << bad;
}

// 30 Hz pairs over `seconds` whose motion errors follow `error(k)` (xi space); every pair
// reports covariance C.
template <typename ErrorOf>
AccuracySummary evaluate(const GroundTruth& gt, const Matrix6d& C, double seconds, ErrorOf error) {
  AccuracyEvaluator evaluator(gt, GroundTruthAllowance{0, 0, "none"});
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  for (int k = 0; k + 1 < static_cast<int>(seconds * 30); ++k) {
    PairResult r;
    r.t_prev_ns = static_cast<std::int64_t>(k) * kSecond / 30;
    r.t_curr_ns = static_cast<std::int64_t>(k + 1) * kSecond / 30;
    const Eigen::Isometry3d truth = true_pose(r.t_prev_ns * 1e-9).inverse() * true_pose(r.t_curr_ns * 1e-9);
    r.T_prev_curr = transform_from_xi(xi_from_transform(truth) + error(k));
    r.covariance = C;
    pose = pose * r.T_prev_curr;
    evaluator.add(r, pose);
  }
  return evaluator.summary();
}

Matrix6d some_covariance() {
  Matrix6d A = Matrix6d::Identity();
  A(1, 3) = 0.5, A(0, 4) = -0.4, A(2, 5) = 0.2;  // correlated axes, as the real ones
  Vector6d sd;
  sd << 0.002, 0.002, 0.0012, 0.002, 0.0018, 0.001;
  return sd.asDiagonal() * (A * A.transpose()) * sd.asDiagonal();
}

// Draws N(0, C) in xi space.
struct Draw {
  Eigen::Matrix<double, 6, 6> L;
  Rng rng;
  explicit Draw(const Matrix6d& C, std::uint64_t seed) : L(C.llt().matrixL()), rng(seed) {}
  Vector6d operator()() {
    Vector6d n;
    for (int i = 0; i < 6; ++i) n(i) = rng.gaussian();
    return L * n;
  }
};

TEST(Consistency, IndependentErrorsOfTheReportedSizeGiveChiSquareSix) {
  const GroundTruth gt = motion_capture(40, 0, 0, 3);
  const Matrix6d C = some_covariance();
  Draw draw(C, 4);
  const AccuracySummary s = evaluate(gt, C, 40, [&](int) { return draw(); });
  // 1199 pairs: the mean of chi2(6) scatters by 0.1, the fraction below the gate by 0.006.
  EXPECT_NEAR(s.pair_nees.mean, 6.0, 0.35);
  EXPECT_NEAR(s.pair_nees.within_95, 0.95, 0.02);
  for (int a = 0; a < 6; ++a) {
    EXPECT_NEAR(s.axis_nees(a), 1.0, 0.12) << a;
    EXPECT_NEAR(s.axis_within_3sigma(a), 0.9973, 0.006) << a;
    EXPECT_NEAR(s.lag1_correlation(a), 0.0, 0.09) << a;
  }
  // Overlapping windows of 30 pairs: ~40 independent ones, mean within ~+-1.3 (1 sigma);
  // measured 5.3.
  EXPECT_GT(s.window_nees.count, 1000);
  EXPECT_NEAR(s.window_nees.mean, 6.0, 1.5);
}

TEST(Consistency, PersistentErrorsShowOverWindowsAndInTheLagOneCorrelation) {
  // AR(1) errors with coefficient 0.6, each of the reported size: right per pair, but their
  // sum over 30 pairs has ~(1 + 0.6) / (1 - 0.6) = 4x the variance a filter would assume.
  const GroundTruth gt = motion_capture(40, 0, 0, 3);
  const Matrix6d C = some_covariance();
  Draw draw(C, 5);
  Vector6d e = draw();
  const AccuracySummary s = evaluate(gt, C, 40, [&](int) {
    e = 0.6 * e + 0.8 * draw();
    return e;
  });
  EXPECT_NEAR(s.pair_nees.mean, 6.0, 0.6);
  for (int a = 0; a < 6; ++a) EXPECT_NEAR(s.lag1_correlation(a), 0.6, 0.08) << a;
  EXPECT_NEAR(s.window_nees.mean, 24.0, 6.0);  // measured 23.5
}

TEST(Consistency, ErrorsSharedByConsecutivePairsCancelOverWindows) {
  // A frame's error enters the pair before it and the pair after it with opposite signs:
  // e_k = n_k - n_(k-1), reported 2C; lag-1 correlation -1/2; over a window the sum telescopes
  // to two frames' errors, far below the 30 x 2C a filter would assume.
  const GroundTruth gt = motion_capture(40, 0, 0, 3);
  const Matrix6d C = some_covariance();
  Draw draw(C, 6);
  Vector6d last = draw();
  const AccuracySummary s = evaluate(gt, 2 * C, 40, [&](int) {
    const Vector6d now = draw();
    const Vector6d e = now - last;
    last = now;
    return e;
  });
  EXPECT_NEAR(s.pair_nees.mean, 6.0, 0.5);
  for (int a = 0; a < 6; ++a) EXPECT_NEAR(s.lag1_correlation(a), -0.5, 0.07) << a;
  EXPECT_LT(s.window_nees.mean, 0.5);  // measured 0.20
}

TEST(Consistency, TheAllowanceAccountsForNoisyGroundTruth) {
  // Reported covariance right for the odometry, ground truth jittering by 0.15 mm / 0.06 deg:
  // without the allowance, the tight rotation axes look inconsistent.
  const GroundTruth gt = motion_capture(40, 0.00015, 0.001, 7);
  Vector6d sd;
  sd << 0.0005, 0.0005, 0.0005, 0.0005, 0.0005, 0.0005;
  const Matrix6d C = sd.cwiseAbs2().asDiagonal();
  const auto run = [&](const GroundTruthAllowance& a) {
    AccuracyEvaluator evaluator(gt, a);
    Draw draw(C, 8);
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    for (int k = 0; k + 1 < 1200; ++k) {
      PairResult r;
      r.t_prev_ns = static_cast<std::int64_t>(k) * kSecond / 30;
      r.t_curr_ns = static_cast<std::int64_t>(k + 1) * kSecond / 30;
      const Eigen::Isometry3d truth = true_pose(r.t_prev_ns * 1e-9).inverse() * true_pose(r.t_curr_ns * 1e-9);
      r.T_prev_curr = transform_from_xi(xi_from_transform(truth) + draw());
      r.covariance = C;
      pose = pose * r.T_prev_curr;
      evaluator.add(r, pose);
    }
    return evaluator.summary();
  };
  const AccuracySummary without = run({0, 0, "none"});
  const AccuracySummary with = run(allowance_from(estimate_groundtruth_noise(gt.poses())));
  EXPECT_GT(without.pair_nees.mean, 15.0);  // measured 22.0
  // The allowance is conservative (a ground-truth pose interpolated between two samples is
  // less noisy than one sample), so a little below 6: measured 4.86.
  EXPECT_GT(with.pair_nees.mean, 4.3);
  EXPECT_LT(with.pair_nees.mean, 5.6);
}

TEST(Consistency, AnErrorPersistingInOneAxisShowsInThatAxisOverWindows) {
  // tz errors AR(1) with coefficient 0.9 (a slow drift of the depth), the others independent,
  // each of the reported size: over 30 pairs tz has up to (1 + 0.9) / (1 - 0.9) = 19x the
  // variance summed (~13 for windows this short), the other axes ~1.
  const GroundTruth gt = motion_capture(40, 0, 0, 3);
  Vector6d sd;
  sd << 0.002, 0.002, 0.0012, 0.002, 0.0018, 0.001;
  const Matrix6d C = sd.cwiseAbs2().asDiagonal();
  Draw draw(C, 9);
  double tz = 0;
  const AccuracySummary s = evaluate(gt, C, 40, [&](int) {
    Vector6d e = draw();
    tz = 0.9 * tz + std::sqrt(1 - 0.81) * e(2);
    e(2) = tz;
    return e;
  });
  EXPECT_NEAR(s.axis_nees(2), 1.0, 0.2);  // right per pair
  EXPECT_GT(s.window_axis_nees(2), 8.0);  // measured 16.5
  for (int a : {0, 1, 3, 4, 5}) EXPECT_NEAR(s.window_axis_nees(a), 1.0, 0.35) << a;  // measured 0.77-1.10
}

// Pairs whose rotations were taken `rotation_lag_s` before the stamps, and whose tz
// `depth_lag_s` before, on the swinging camera; every pair reports a 1 mm / 1 mrad covariance.
AccuracySummary lagged(const GroundTruth& gt, double rotation_lag_s, double depth_lag_s) {
  AccuracyEvaluator evaluator(gt, GroundTruthAllowance{0, 0, "none"});
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  const auto motion = [](double t0, double t1) { return swinging_pose(t0).inverse() * swinging_pose(t1); };
  for (int k = 3; k < 290; ++k) {
    PairResult r;
    r.t_prev_ns = static_cast<std::int64_t>(k) * kSecond / 30;
    r.t_curr_ns = static_cast<std::int64_t>(k + 1) * kSecond / 30;
    const double t0 = r.t_prev_ns * 1e-9, t1 = r.t_curr_ns * 1e-9;
    r.T_prev_curr = motion(t0 - rotation_lag_s, t1 - rotation_lag_s);
    r.T_prev_curr.translation().z() = motion(t0 - depth_lag_s, t1 - depth_lag_s).translation().z();
    r.covariance = Matrix6d::Identity() * 1e-6;
    pose = pose * r.T_prev_curr;
    evaluator.add(r, pose);
  }
  return evaluator.summary();
}

TEST(TimeOffset, TheStreamsLatenciesAreRecoveredFromTheRotationsAndTz) {
  const GroundTruth gt = motion_capture(10, 0, 0, 1, swinging_pose);
  for (const auto& [colour_ms, depth_ms] : {std::pair{14.0, 40.0}, std::pair{-7.0, 0.0}, std::pair{0.0, 25.0}}) {
    const AccuracySummary s = lagged(gt, colour_ms * 1e-3, depth_ms * 1e-3);
    const TimeOffsetFit& c = s.rotation_time_offset;
    const TimeOffsetFit& d = s.depth_time_offset;
    ASSERT_TRUE(c.found && d.found) << colour_ms << " " << depth_ms;
    EXPECT_EQ(c.pairs, 287);  // every pair: the ground truth covers +-60 ms around each
    // The ground truth interpolated between 100 Hz samples, and the parabola between 1 ms
    // steps: measured within 0.005 ms.
    EXPECT_NEAR(c.offset_s * 1e3, colour_ms, 0.05);
    EXPECT_NEAR(d.offset_s * 1e3, depth_ms, 0.05);
    if (colour_ms != 0) {
      EXPECT_LT(c.rmse_at_offset, 0.05 * c.rmse_at_stamps);  // measured 0.015, 0.035
    }
    EXPECT_LE(c.rmse_at_offset, c.rmse_at_stamps);
  }
}

TEST(TimeOffset, ItsStandardErrorIsTheSpreadOfTheOffsetsFound) {
  // GIVEN the colour 14 ms and the depth 40 ms late, each pair's rotation noisy by 0.5 mrad
  // per axis and its tz by 0.5 mm, drawn again 40 times
  const GroundTruth gt = motion_capture(10, 0, 0, 1, swinging_pose);
  const auto motion = [](double t0, double t1) { return swinging_pose(t0).inverse() * swinging_pose(t1); };
  std::vector<double> colour, depth;
  double colour_se = 0, depth_se = 0;
  for (unsigned seed = 0; seed < 40; ++seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> g(0, 5e-4);
    AccuracyEvaluator evaluator(gt, GroundTruthAllowance{0, 0, "none"});
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    for (int k = 3; k < 290; ++k) {
      PairResult r;
      r.t_prev_ns = static_cast<std::int64_t>(k) * kSecond / 30;
      r.t_curr_ns = static_cast<std::int64_t>(k + 1) * kSecond / 30;
      const double t0 = r.t_prev_ns * 1e-9, t1 = r.t_curr_ns * 1e-9;
      Vector6d xi = xi_from_transform(motion(t0 - 0.014, t1 - 0.014));
      for (int a = 3; a < 6; ++a) xi(a) += g(rng);
      r.T_prev_curr = transform_from_xi(xi);
      r.T_prev_curr.translation().z() = motion(t0 - 0.040, t1 - 0.040).translation().z() + g(rng);
      r.covariance = Matrix6d::Identity() * 1e-6;
      pose = pose * r.T_prev_curr;
      evaluator.add(r, pose);
    }
    const AccuracySummary s = evaluator.summary();
    ASSERT_TRUE(s.rotation_time_offset.found && s.depth_time_offset.found);
    colour.push_back(s.rotation_time_offset.offset_s);
    depth.push_back(s.depth_time_offset.offset_s);
    colour_se += s.rotation_time_offset.standard_error_s / 40;
    depth_se += s.depth_time_offset.standard_error_s / 40;
  }
  // THEN the standard error each fit reports is the spread of the offsets over the draws
  // (measured: 1.11x for the rotations' and 0.99x for tz's, over 40 draws; counting the
  // rotation's angle as one residual, not three, made it 1.7x)
  const auto spread = [](const std::vector<double>& v) {
    double mean = 0, var = 0;
    for (double x : v) mean += x / static_cast<double>(v.size());
    for (double x : v) var += (x - mean) * (x - mean) / static_cast<double>(v.size() - 1);
    return std::sqrt(var);
  };
  EXPECT_NEAR(colour_se / spread(colour), 1.0, 0.25);
  EXPECT_NEAR(depth_se / spread(depth), 1.0, 0.25);
}

TEST(TimeOffset, NoneIsFoundBeyondTheSearchOrWithTooFewPairs) {
  const GroundTruth gt = motion_capture(10, 0, 0, 1, swinging_pose);
  const AccuracySummary far = lagged(gt, 0.1, 0.0);  // 100 ms: beyond +-60 ms
  EXPECT_FALSE(far.rotation_time_offset.found);
  EXPECT_GT(far.rotation_time_offset.pairs, 0);
  EXPECT_TRUE(far.depth_time_offset.found);
  // A 200-ms hole in the ground truth (the motion capture lost the markers): the pairs whose
  // shifts would reach into it are left out, and the fit still finds the lag.
  std::vector<StampedPose> holed;
  for (const StampedPose& p : gt.poses())
    if (p.t_ns < 5 * kSecond || p.t_ns > 5 * kSecond + kSecond / 5) holed.push_back(p);
  const AccuracySummary with_hole = lagged(GroundTruth(holed), 0.014, 0.0);
  ASSERT_TRUE(with_hole.rotation_time_offset.found);
  EXPECT_NEAR(with_hole.rotation_time_offset.offset_s * 1e3, 14.0, 0.05);
  // Ground truth for only 0.6 s: fewer than 30 pairs covered at every offset.
  const GroundTruth short_gt = motion_capture(0.6, 0, 0, 1, swinging_pose);
  const AccuracySummary few = lagged(short_gt, 0.01, 0.01);
  EXPECT_FALSE(few.rotation_time_offset.found);
  EXPECT_EQ(few.rotation_time_offset.pairs, 0);
}

}  // namespace
}  // namespace rgbdo
