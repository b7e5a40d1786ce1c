#pragma once
// The pipeline's settings, one struct a stage, and the keys they are set by (core/settings.hpp).
// Loaded and validated once at start-up (app/config.hpp); the hot path only reads these fields.
#include <array>
#include <cstdint>
#include <string>
#include <string_view>

#include "rgbd_odometry/core/camera_mount.hpp"
#include "rgbd_odometry/core/settings.hpp"

namespace rgbdo {

struct CameraConfig {
  int width = 640;
  int height = 480;
  double fx = 525.0, fy = 525.0, cx = 319.5, cy = 239.5;
  // OpenCV order: k1, k2, p1, p2, k3.
  std::array<double, 5> distortion{0, 0, 0, 0, 0};
};

struct DepthConfig {
  double units_per_m = 5000.0;  // raw uint16 value per metre (TUM: 5000, OpenNI mm: 1000)
  double min_m = 0.4;           // PrimeSense sensors give no reliable depth below ~0.4 m
  double max_m = 4.5;           // beyond ~4.5 m sigma_Z exceeds 3 cm: useless for odometry
  // A keypoint whose 5x5 depth neighbourhood spans more than this fraction of its depth sits
  // on an occlusion edge, where colour and depth disagree; it is not back-projected.
  double edge_max_relative_step = 0.03;
  // Correct each keypoint's depth from the depth frame's capture time to the colour frame's
  // (the streams of PrimeSense sensors are not synchronised; TUM fr1 is up to 17 ms apart).
  bool compensate_timing = true;
  // Where the depth image is misregistered against the colour: a surface the colour image shows
  // at pixel (u, v) is in the depth image at (u - registration_x_px, v - registration_y_px).
  // A sensor's registration (TUM fr1's Kinect: +0.77, -1.11 px) is read from its recording's
  // occlusion edges by bench/depth_lag_edges.py.
  double registration_x_px = 0.0;
  double registration_y_px = 0.0;
  // How much earlier than its stamps say, relative to its colour frame, a depth frame is taken
  // (its lag, seconds; negative: later): the optical axis's share of the motion is carried to the
  // colour's instants by it (pipeline/depth_clock.hpp). Read from a recording's occlusion edges
  // by bench/depth_lag_edges.py (its age less what the stamps show; TUM fr1's Kinect: 17 ms).
  double lag_beyond_stamps_s = 0.0;
  // How much earlier than the stamps the tilt rotations (about the image's x and y axes) are
  // measured, the depth's lag leaking into them through the slide: each frame's tilt is carried
  // by this × its turning rate, its image shift kept (pipeline/depth_clock.hpp). Not carried
  // where a gyro times the rotations. TUM fr1's Kinect: 13 ms measured, 7 carried.
  double tilt_lag_beyond_stamps_s = 0.0;
};

// What features.detector and features.descriptor may name: the project's own extractor
// (pipeline/grid_orb.hpp, detector and descriptor together) and OpenCV's Feature2D algorithms.
inline constexpr std::string_view kGridOrb = "GRID_ORB";
inline constexpr std::array<std::string_view, 9> kFeatureDetectors{"GRID_ORB", "ORB",  "AKAZE", "BRISK", "SIFT",
                                                                   "KAZE",     "FAST", "GFTT",  "AGAST"};
inline constexpr std::array<std::string_view, 6> kFeatureDescriptors{"GRID_ORB", "ORB", "AKAZE", "BRISK", "SIFT", "KAZE"};

struct FeatureConfig {
  std::string detector = "GRID_ORB";  // ours (pipeline/grid_orb.hpp); OpenCV's by name for comparison
  std::string descriptor = "GRID_ORB";
  int max_features = 1000;
  int border_px = 16;  // the image periphery dropped before detection (distortion is worst there)
  // ORB's scale pyramid (OpenCV's defaults: 8 levels, factor 1.2) and FAST threshold.
  int orb_levels = 8;
  double orb_scale_factor = 1.2;
  int fast_threshold = 20;
};

struct MatchConfig {
  double ratio = 0.8;  // lambda_ratio: best / second-best distance must be below this
  // Search window (pixels, half width) around where the motion prior puts each previous
  // keypoint in the current frame; 0 compares every pair, as the paper does. A pair whose
  // windowed search fails, or keeps fewer than twice ransac.min_inliers, is matched again
  // over the whole image. Binary descriptors only (float ones always compare every pair).
  double window_px = 48;
  // Each matched keypoint of the current frame moved to where the previous keypoint's patch
  // lies, to a fraction of a pixel (pipeline/track.hpp); off: the detector's integer corners,
  // as the paper (its covariance model never tracks).
  bool subpixel_tracking = true;
};

struct RansacConfig {
  double inlier_threshold_m = 0.05;  // lambda_inlier
  int max_iterations = 200;
  bool refine_threshold = true;  // threshold <- min(3 sigma_inliers, lambda_inlier)
  int min_inliers = 12;          // fewer than this and the pair is reported as failed
  // Stop sampling once an all-inlier sample has been drawn with 99.9 % probability.
  bool adaptive_stop = true;
};

// The depth alignment that refines the feature motion (pipeline/depth_alignment.hpp).
struct RefinementConfig {
  bool enabled = true;
  int stride_px = 8;               // the depth maps sampled every this many pixels
  bool average_depth = true;       // each sample the mean of the 5x5 pixels around it, where they are one surface
  int iterations = 4;              // Gauss-Newton steps at most
  double max_distance_m = 0.05;    // a point further than this from its associated one is not used
  int min_points = 300;            // fewer associations and the feature motion stands alone
  double cell_px = 80;             // image cells whose residuals may be correlated (the covariance's clusters)
  // The alignment's sigma is scaled by factors learnt against the features
  // (depth_alignment.hpp, AlignmentTrust): their start, step per pair and ceiling (floor 1).
  double sigma_scale_prior = 4;
  double sigma_scale_rate = 0.1;
  double sigma_scale_max = 1000;
  // Fused only while both factors are at most this (pair_estimator.cpp says why).
  double max_sigma_scale_fused = 2.5;
  // The depth's lag behind the colour (beyond the stamps), learnt from the two estimates and
  // reported (DepthLagEstimate), at most this much either way, seconds.
  double max_depth_lag_s = 0.1;
  // Fused only while that learnt lag is at most this either way, seconds (pair_estimator.cpp
  // says why).
  double max_depth_lag_fused_s = 0.015;
  // Where either of those refuses it, the alignment is fused with its sigma scaled by these
  // fixed factors instead: sideways translation (x, y), translation along the optical axis,
  // rotation (0: the features stand alone; pair_estimator.cpp says why).
  double distrusted_sigma_scale = 40;
  double distrusted_sigma_scale_optical_axis = 120;
  double distrusted_sigma_scale_rotation = 100;
};

// Keyframes (pipeline/keyframes.hpp): each frame measured against a kept earlier frame as well,
// so that a camera over one view reports the same place every time it comes back.
struct KeyframeConfig {
  bool enabled = true;
  int kept = 4;  // recent keyframes kept for a return to an earlier view
  // A keyframe is held while the current frame's inliers against it are at least this share
  // of those its first measured frame had, and at least twice ransac.min_inliers.
  double min_inlier_share = 0.5;
  // The share of the keyframe's disagreement with the frame pairs' prediction taken per frame.
  double gain = 0.15;
};

inline constexpr std::array<std::string_view, 2> kCovarianceModels{"physical", "paper"};

struct CovarianceConfig {
  int perturbations = 100;
  // "physical" (pipeline/noise_model.hpp: keypoint error by pyramid level, axial and lateral depth
  // noise, capture-time error) or "paper" (Willis & Brink eq. 2 only, for comparison).
  std::string model = "physical";
  double depth_noise_coeff = 1.425e-3;  // sigma_Z = coeff * Z^2 (Khoshelham & Elberink 2012), 1/m
  // Keypoint localisation error at full resolution: corners found on the integer pixel grid
  // without sub-pixel refinement are off by a uniform +-0.5 px, sigma 1/sqrt(12) = 0.289 px;
  // a pyramid level's grid is features.orb_scale_factor^level coarser. Also weights the fit.
  double pixel_sigma_px = 0.289;
  // Lateral noise of the depth map (Nguyen, Izadi & Lovell 2012, Kinect: ~0.8 px): a depth is
  // read where the surface is off by this much sideways, which matters where depth is steep.
  double depth_lateral_sigma_px = 0.8;
  // Standard deviation of a frame's colour-to-depth capture-time offset error, seconds; < 0:
  // estimated online from the jitter of the streams' own frame intervals.
  double timing_sigma_s = -1;
  // What the stamps get wrong in common, frame after frame (pipeline/latency_covariance.hpp):
  // sigma of the colour stream's capture latency behind its stamps, and of the depth stream's
  // behind the colour, seconds; 0: calibrated away. Against motion capture, TUM fr1's Kinect
  // v1 takes its depth 25-28 ms after its colour, which no consumer can correct
  // (src/pipeline/README.md#noise-model-and-covariance): depth 25 ms. Its colour lags the stamps
  // by 14-19 ms, a constant delay a flight controller is told (PX4 EKF2_EV_DELAY, ArduPilot
  // VISO_DELAY_MS) and which the odometry only has to cover in part: colour 7.5 ms, half of it.
  double colour_latency_sigma_s = 0.0075;
  double depth_latency_sigma_s = 0.025;
  // The horizon over which a consumer integrating the reported motions should stay covered
  // against those latencies, seconds (each pair carries its share); 0: per pair only.
  double integration_window_s = 1.0;
  // Each perturbation also resamples the inliers by image cells of this size (pixels; a
  // Bayesian bootstrap by cell, covariance.hpp): errors that vary smoothly over the image are
  // shared by a cell's points. 0: no resampling.
  double resample_cell_px = 160;
  // Multiply the noise by the fit's a-posteriori variance factor (covariance.hpp); false: the paper.
  bool residual_variance_factor = true;
  // Multiplies the covariance before it is reported; 1: the noise model as it stands.
  double scale = 1.0;
  // What goes out is the running (log-Euclidean) mean of the pairs' rate covariances over this
  // time, seconds, not each pair's own (pipeline/reported_covariance.hpp); 0: each pair's own.
  double smoothing_s = 1.0;
  // ... except where a pair's own is wider in some direction: there it weighs in from
  // sqrt(this) times as wide (in variance) and goes out as its own from this; 0: never. 9 is
  // 3x in sigma, weighing in from 1.7x: a pair's own excess over the mean is error, not noise
  // of the estimate (fr1_xyz with a gyro, binned by that excess: 3.7-4.6 NEES against their own
  // covariance in every bin, while against a mean passing them from 2.2x in sigma the widest
  // tenth scored 6.9, 83 % under the gate; its thinned copies alike; src/pipeline/MEASUREMENTS.md).
  double smoothing_pass_ratio = 9;
};

// When the frames were taken, measured against the autopilot's gyro (pipeline/capture_latency.hpp):
// live, the followed autopilot's ATTITUDE rates; a replay, the recording's imu.txt or --imu.
// Without either, the stamps stand and the covariance keeps covariance.*_latency_sigma_s.
struct LatencyConfig {
  bool enabled = true;  // measure and apply it when there are gyro samples
  // The offsets (stamp minus capture instant, on the gyro's clock) searched, seconds.
  double min_s = -0.1, max_s = 0.25;
  // What a moving camera's evidence is worth over time: older pairs weigh e^(-age / memory_s),
  // so a latency that changes slowly (a host clock, a USB hub) is followed. A camera at rest
  // forgets nothing: it shows nothing of the latency.
  double memory_s = 30;
  // Applied once its standard error is this small (before: the stamps, and the priors).
  double converged_sigma_s = 0.005;
  // How fast the applied latency may move towards the estimate at most (it moves a tenth of
  // the way a frame): seconds per second of frames, so that no two frames change order and a
  // consumer's velocities are not jolted.
  double max_slew = 0.05;
  // A measured camera mount further than this from body.* is warned about, degrees.
  double mount_warning_deg = 5;
  // Move the pairs' image shift to their times where the colour image's own latency is told
  // apart from the depth's (CaptureClock::image_shift_retime_s); off: it stays on the stamps
  // and the covariance covers the whole restamp.
  bool retime_image_shift = true;
};

// Every setting of the pipeline: what each stage and the capture-latency measurement read.
struct PipelineConfig {
  CameraConfig camera;
  DepthConfig depth;
  FeatureConfig features;
  MatchConfig matching;
  RansacConfig ransac;
  CovarianceConfig covariance;
  RefinementConfig refinement;
  KeyframeConfig keyframes;
  LatencyConfig latency;
  BodyConfig body;  // the camera's mount (core/camera_mount.hpp): the gyro's rates are the body's
  std::uint64_t seed = 1;  // with the two frames' content, seeds RANSAC and the perturbations (pair_estimator.cpp)
};

// The keys camera.* to latency.*, in that order, into `table` (pointing into c).
void add_pipeline_settings(PipelineConfig& c, SettingsTable& table);
// The key `seed`.
void add_seed_setting(PipelineConfig& c, SettingsTable& table);
// Throws ConfigError naming the first key whose value does not fit the others (ranges are the
// table's: check_ranges).
void validate_pipeline(const PipelineConfig& c);

}  // namespace rgbdo
