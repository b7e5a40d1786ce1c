#pragma once
// --calibrate FILE: a recording of the user's sensor with motion-capture ground truth turns
// into a configuration that holds that sensor's constants, which --config then reads. Optional:
// the shipped defaults need none of it (the depth noise, the keypoints' localisation and the
// alignment's trust are learnt on every run); what a calibration adds is what only the ground
// truth shows:
//  - the streams' capture latencies (eval/evaluate.hpp's time offsets: the rotations for the
//    colour, tz for the depth). A latency the stamps do not show is an error of every pair of
//    the size latency x change of rate (pipeline/latency_covariance.hpp); its RMS over the run
//    is the latency itself, known to the fit's standard error, so
//    covariance.colour_latency_sigma_s = hypot(colour's, its error) and
//    covariance.depth_latency_sigma_s = hypot(depth's - colour's, their errors);
//  - where the run learnt a constant from the data, it is written as the next run's start:
//    covariance.depth_noise_coeff (the depth maps' noise) and refinement.sigma_scale_prior
//    (the alignment's trust), so that the next run does not spend its first pairs learning
//    them again.
// Measured on ICL-NUIM kt3, calibrated on images 0-49 and run on 50-99: pair RPE 0.78 ->
// 0.067 mm, pair NEES (no allowance) 3.81 -> 5.53
// (src/pipeline/MEASUREMENTS.md#calibration-against-ground-truth-optional).
#include <string>

#include "rgbd_odometry/app/config.hpp"
#include "rgbd_odometry/core/sensor_estimates.hpp"
#include "rgbd_odometry/eval/evaluate.hpp"

namespace rgbdo {

struct Calibration {
  Config config;      // the run's configuration with the calibrated keys set
  std::string notes;  // what was measured and what was set, as '#' comment lines
  bool changed = false;  // any key set (false: nothing could be measured)
};

// The run's configuration, what it measured against the ground truth and what it learnt.
// `learnt`: the last pair's estimates (all zero when the depth alignment was off).
Calibration calibrate(const Config& run_config, const AccuracySummary& summary, const SensorEstimates& learnt);

// The file: the notes, then the whole configuration as --print-config writes it.
std::string calibration_yaml(const Calibration& calibration);

}  // namespace rgbdo
