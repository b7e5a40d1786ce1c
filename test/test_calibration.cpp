#include "rgbd_odometry/app/calibration.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>

#include "rgbd_odometry/app/config_file.hpp"

namespace rgbdo {
namespace {

TimeOffsetFit offset(double offset_s, double standard_error_s) {
  TimeOffsetFit f;
  f.found = true;
  f.offset_s = offset_s;
  f.standard_error_s = standard_error_s;
  f.max_offset_s = 0.1;
  f.pairs = 100;
  return f;
}

TEST(Calibration, TakesTheMeasuredLatenciesWithTheirUncertainty) {
  // GIVEN colour taken 14 +- 1 ms and depth 45 +- 3 ms before their stamps, and what the run learnt
  AccuracySummary s;
  s.evaluated = 100;
  s.rotation_time_offset = offset(0.014, 0.001);
  s.depth_time_offset = offset(0.045, 0.003);
  SensorEstimates learnt;
  learnt.depth_noise_coeff = 2.1e-3;
  learnt.depth_sigma_scale_t = 6.3;
  learnt.depth_sigma_scale_r = 3.3;
  // WHEN calibrated
  const Calibration c = calibrate(Config{}, s, learnt);
  // THEN each latency sigma is the RMS of what the fit says of it; the learnt constants are the next run's start
  EXPECT_TRUE(c.changed);
  EXPECT_DOUBLE_EQ(c.config.covariance.colour_latency_sigma_s, std::hypot(0.014, 0.001));
  EXPECT_DOUBLE_EQ(c.config.covariance.depth_latency_sigma_s, std::hypot(0.031, std::hypot(0.003, 0.001)));
  EXPECT_DOUBLE_EQ(c.config.covariance.depth_noise_coeff, 2.1e-3);
  EXPECT_DOUBLE_EQ(c.config.refinement.sigma_scale_prior, 6.3);
  // and nothing else moves: the scale stays 1
  EXPECT_EQ(c.config.covariance.scale, 1.0);
  EXPECT_EQ(c.config.covariance.pixel_sigma_px, Config{}.covariance.pixel_sigma_px);
}

TEST(Calibration, ALatencyReadAsZeroIsNotTakenAsExact) {
  AccuracySummary s;
  s.rotation_time_offset = offset(0.0, 0.0004);
  s.depth_time_offset = offset(0.0, 0.0003);
  const Calibration c = calibrate(Config{}, s, SensorEstimates{});
  EXPECT_DOUBLE_EQ(c.config.covariance.colour_latency_sigma_s, 0.0004);
  EXPECT_DOUBLE_EQ(c.config.covariance.depth_latency_sigma_s, 0.0005);
}

TEST(Calibration, WhatWasNotMeasuredIsKeptAndSaid) {
  // GIVEN no offset found (too little rotation) and the depth alignment off (nothing learnt)
  AccuracySummary s;
  s.rotation_time_offset.max_offset_s = 0.1;
  s.rotation_time_offset.pairs = 30;
  Config run;
  run.covariance.colour_latency_sigma_s = 0.011;
  run.covariance.depth_latency_sigma_s = 0.022;
  run.covariance.depth_noise_coeff = 3e-3;
  run.refinement.sigma_scale_prior = 4;
  const Calibration c = calibrate(run, s, SensorEstimates{});
  // THEN the run's own values stay, and the notes say why
  EXPECT_FALSE(c.changed);
  EXPECT_EQ(c.config.covariance.colour_latency_sigma_s, 0.011);
  EXPECT_EQ(c.config.covariance.depth_latency_sigma_s, 0.022);
  EXPECT_EQ(c.config.covariance.depth_noise_coeff, 3e-3);
  EXPECT_EQ(c.config.refinement.sigma_scale_prior, 4);
  EXPECT_NE(c.notes.find("colour latency: not found"), std::string::npos) << c.notes;
  EXPECT_NE(c.notes.find("depth latency: not found"), std::string::npos) << c.notes;
  EXPECT_NE(c.notes.find("not learnt"), std::string::npos) << c.notes;
}

TEST(Calibration, AValueOutsideItsKeysRangeIsSaidAndTheKeyKept) {
  // GIVEN a latency offset beyond the key's 1 s (only a broken clock gives one)
  AccuracySummary s;
  s.rotation_time_offset = offset(1.5, 0.001);
  Config run;
  run.covariance.colour_latency_sigma_s = 0.011;
  const Calibration c = calibrate(run, s, SensorEstimates{});
  EXPECT_EQ(c.config.covariance.colour_latency_sigma_s, 0.011);
  EXPECT_NE(c.notes.find("covariance.colour_latency_sigma_s kept"), std::string::npos) << c.notes;
}

TEST(Calibration, TheFileReadsBackToTheCalibratedValues) {
  AccuracySummary s;
  s.rotation_time_offset = offset(-0.0005, 0.0003);
  s.depth_time_offset = offset(-0.0002, 0.0006);
  SensorEstimates learnt;
  learnt.depth_noise_coeff = 6e-5;
  learnt.depth_sigma_scale_t = 0.5;
  learnt.depth_sigma_scale_r = 1.0;  // the larger
  const Calibration c = calibrate(Config{}, s, learnt);
  const std::string path = ::testing::TempDir() + "rgbdo_calibration.yaml";
  std::ofstream(path) << calibration_yaml(c);
  const Config back = load_config(path);
  std::remove(path.c_str());
  EXPECT_DOUBLE_EQ(back.covariance.colour_latency_sigma_s, c.config.covariance.colour_latency_sigma_s);
  EXPECT_DOUBLE_EQ(back.covariance.depth_latency_sigma_s, c.config.covariance.depth_latency_sigma_s);
  EXPECT_DOUBLE_EQ(back.covariance.depth_noise_coeff, 6e-5);
  EXPECT_DOUBLE_EQ(back.refinement.sigma_scale_prior, 1.0);
}

}  // namespace
}  // namespace rgbdo
