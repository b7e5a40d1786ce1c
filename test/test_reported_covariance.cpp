// What goes out with each motion (pipeline/reported_covariance.hpp): the running
// log-Euclidean mean of the pairs' rate covariances, a pair's own where it is far wider.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "rgbd_odometry/pipeline/reported_covariance.hpp"

namespace rgbdo {
namespace {

constexpr double kFrameS = 1.0 / 30;

// A good pair over dt_s whose rate covariance (its covariance over dt^2) is rate_cov.
PairResult pair_with(const Matrix6d& rate_cov, double dt_s = kFrameS, std::int64_t t_prev_ns = 0) {
  PairResult p;
  p.status = Status::Ok;
  p.t_prev_ns = t_prev_ns;
  p.t_curr_ns = t_prev_ns + static_cast<std::int64_t>(std::llround(dt_s * 1e9));
  p.covariance = rate_cov * (dt_s * dt_s);
  return p;
}

// A covariance with some shape: correlated axes, six different variances.
Matrix6d shaped(double level) {
  Matrix6d a = Matrix6d::Identity();
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) a(i, j) += 0.1 * std::sin(1.0 + i + 2.0 * j);
  Matrix6d c = a * a.transpose();
  c.diagonal() += Vector6d::LinSpaced(0.1, 0.6);
  return level * c;
}

ReportedCovariance reporter(double smoothing_s, double pass_ratio) {
  CovarianceConfig c;
  c.smoothing_s = smoothing_s;
  c.smoothing_pass_ratio = pass_ratio;
  return ReportedCovariance(c);
}

// `pairs` one-frame pairs of rate covariance q, from time 0: the time after them.
std::int64_t settle(ReportedCovariance& reported, const Matrix6d& q, int pairs) {
  std::int64_t t = 0;
  for (int i = 0; i < pairs; ++i, t += 33'333'333LL) {
    PairResult p = pair_with(q, kFrameS, t);
    reported.report(p);
  }
  return t;
}

double relative_difference(const Matrix6d& a, const Matrix6d& b) { return (a - b).norm() / b.norm(); }

TEST(ReportedCovariance, AnUnchangingCovarianceGoesOutAsItIs) {
  ReportedCovariance reported = reporter(1.0, 9.0);
  const Matrix6d q = shaped(0.01);
  for (int i = 0; i < 60; ++i) {
    PairResult p = pair_with(q, kFrameS, i * 33'333'333LL);
    const Matrix6d own = p.covariance;
    reported.report(p);
    ASSERT_LT(relative_difference(p.covariance, own), 1e-9) << "pair " << i;
  }
}

TEST(ReportedCovariance, ALevelThatAlternatesGoesOutAsItsGeometricMean) {
  // Pairs alternately 4x apart in variance: what goes out settles at 2x the lower one (the
  // geometric mean), where the arithmetic mean would be 2.5x; it still sways a little with
  // each pair, by the mean's weight per pair (1 - e^(-dt/1 s)) on log 4.
  ReportedCovariance reported = reporter(1.0, 0.0);
  const Matrix6d low = shaped(0.01);
  Matrix6d last_low_out = Matrix6d::Zero(), last_high_out = Matrix6d::Zero();
  for (int i = 0; i < 400; ++i) {
    PairResult p = pair_with(i % 2 == 0 ? low : 4.0 * low, kFrameS, i * 33'333'333LL);
    reported.report(p);
    (i % 2 == 0 ? last_low_out : last_high_out) = p.covariance / (kFrameS * kFrameS);
  }
  const double sway = 1.0 - std::exp(-kFrameS / 1.0);  // 0.033 of log 4 = 4.7 %
  EXPECT_LT(relative_difference(last_low_out, 2.0 * low), sway);
  EXPECT_LT(relative_difference(last_high_out, 2.0 * low), sway);
  EXPECT_GT(relative_difference(last_high_out, last_low_out), 0.5 * sway);  // it is a running mean
}

TEST(ReportedCovariance, AStepIsFollowedOverTheSmoothingTime) {
  // From one level to 100x it: after smoothing_s of pairs the log of what goes out has come
  // 1 - 1/e of the way, and after five times that all but 1 %.
  ReportedCovariance reported = reporter(1.0, 0.0);
  const Matrix6d q = shaped(0.01);
  std::int64_t t = settle(reported, q, 90);
  auto level_after = [&](int pairs) {
    PairResult p;
    for (int i = 0; i < pairs; ++i, t += 33'333'333LL) {
      p = pair_with(100.0 * q, kFrameS, t);
      reported.report(p);
    }
    return std::log((p.covariance / (kFrameS * kFrameS)).trace() / q.trace()) / std::log(100.0);
  };
  EXPECT_NEAR(level_after(30), 1.0 - std::exp(-30 * kFrameS), 0.01);
  EXPECT_GT(level_after(120), 0.99);
}

// After a steady level 1e-4 I, one pair wider along x alone by `wider` (in variance): what
// goes out along x, over the mean there (the other axes stay the mean's).
double reported_along_x(double wider, double pass_ratio) {
  ReportedCovariance reported = reporter(1.0, pass_ratio);
  const Matrix6d q = 1e-4 * Matrix6d::Identity();
  std::int64_t t = settle(reported, q, 90);
  Matrix6d wide = q;
  wide(0, 0) *= wider;
  PairResult p = pair_with(wide, kFrameS, t);
  reported.report(p);
  const double mean = p.covariance(1, 1);
  EXPECT_NEAR(mean, q(1, 1) * kFrameS * kFrameS, 1e-6 * mean);
  for (int a = 2; a < 6; ++a) EXPECT_NEAR(p.covariance(a, a), mean, 1e-6 * mean) << "axis " << a;
  return p.covariance(0, 0) / mean;
}

TEST(ReportedCovariance, APairFarWiderThanTheMeanGoesOutWithItsOwnWhereItIsWider) {
  // Features starving sideways: 100x wider along x goes out as its own there (the mean itself
  // moved by the pair's weight, 3.3 % of log 100: 16 %).
  const double weight = 1.0 - std::exp(-kFrameS / 1.0);
  const double mean_x = std::exp(weight * std::log(100.0));
  EXPECT_NEAR(reported_along_x(100.0, 9.0), 100.0, 1e-6 * 100.0);
  // Without the pass, only the mean's step.
  EXPECT_NEAR(reported_along_x(100.0, 0.0), mean_x, 1e-6 * mean_x);
  // Between sqrt(9) and 9 times as wide it weighs in, continuously: lambda^2 / 9 over the mean
  // (the mean's own step along x taken out).
  const double lambda4 = 4.0 / std::exp(weight * std::log(4.0));
  EXPECT_NEAR(reported_along_x(4.0, 9.0) / std::exp(weight * std::log(4.0)), lambda4 * lambda4 / 9.0, 1e-6);
  // Within the ordinary spread, the mean.
  EXPECT_NEAR(reported_along_x(2.0, 9.0), std::exp(weight * std::log(2.0)), 1e-6);
}

TEST(ReportedCovariance, ItFollowsTheRateSoALongerPairGoesOutWider) {
  // A frame dropped: the pair spans two frame times. The same rate covariance, so what goes
  // out is 4x the one-frame pair's, as the pair's own is.
  ReportedCovariance reported = reporter(1.0, 9.0);
  const Matrix6d q = shaped(0.01);
  std::int64_t t = settle(reported, q, 30);
  PairResult longer = pair_with(q, 2 * kFrameS, t);
  const Matrix6d own = longer.covariance;
  reported.report(longer);
  EXPECT_LT(relative_difference(longer.covariance, own), 1e-6);  // the stamps are whole nanoseconds
}

TEST(ReportedCovariance, FailedPairsPassAndALostSensorStartsTheMeanAgain) {
  ReportedCovariance reported = reporter(1.0, 0.0);
  std::int64_t t = settle(reported, shaped(0.01), 60);
  PairResult failed;
  failed.status = Status::RansacFailed;
  reported.report(failed);
  EXPECT_FALSE(failed.covariance.allFinite());  // NaN, as every failed pair reports

  // After a failed pair the mean carries on: a pair 10x wider is mostly the old mean.
  PairResult after_failure = pair_with(shaped(0.1), kFrameS, t);
  reported.report(after_failure);
  EXPECT_LT(after_failure.covariance.trace(), 0.2 * shaped(0.1).trace() * kFrameS * kFrameS);

  // After a lost sensor, whatever was learnt before is not this scene's: the first pair goes
  // out with its own.
  PairResult lost;
  lost.status = Status::SensorLost;
  reported.report(lost);
  t += 10 * 33'333'333LL;
  PairResult first = pair_with(shaped(0.1), kFrameS, t);
  const Matrix6d own = first.covariance;
  reported.report(first);
  EXPECT_LT(relative_difference(first.covariance, own), 1e-9);
}

TEST(ReportedCovariance, OffEveryPairGoesOutWithItsOwn) {
  ReportedCovariance reported = reporter(0.0, 9.0);
  for (int i = 0; i < 10; ++i) {
    PairResult p = pair_with(shaped(0.01 * (1 + i % 3)), kFrameS, i * 33'333'333LL);
    const Matrix6d own = p.covariance;
    reported.report(p);
    EXPECT_EQ(p.covariance, own);
  }
}

TEST(ReportedCovariance, ACovarianceThatIsNotPositiveDefiniteGoesOutUntouched) {
  // Not the reporter's to mend (a pair that breaks the promise is caught where it is sent).
  ReportedCovariance reported = reporter(1.0, 9.0);
  PairResult p = pair_with(shaped(0.01));
  p.covariance(2, 2) = -1.0;
  const Matrix6d own = p.covariance;
  reported.report(p);
  EXPECT_EQ(p.covariance, own);
}

}  // namespace
}  // namespace rgbdo
