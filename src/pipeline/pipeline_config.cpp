#include "rgbd_odometry/pipeline/pipeline_config.hpp"

#include <algorithm>
#include <limits>

namespace rgbdo {

void add_pipeline_settings(PipelineConfig& c, SettingsTable& table) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  table.insert(table.end(), {
      {"camera.width", "px", "image width the intrinsics are for; frames of another size are refused", &c.camera.width, 16, 8192},
      {"camera.height", "px", "image height the intrinsics are for", &c.camera.height, 16, 8192},
      {"camera.fx", "px", "focal length along x (calibrated; or camera.calibration_file)", &c.camera.fx, 1, 1e5},
      {"camera.fy", "px", "focal length along y", &c.camera.fy, 1, 1e5},
      {"camera.cx", "px", "principal point x", &c.camera.cx, 0, 8192},
      {"camera.cy", "px", "principal point y", &c.camera.cy, 0, 8192},
      {"camera.k1", "", "radial distortion k1 (OpenCV order; in a file also camera.distortion: [k1, k2, p1, p2, k3])", &c.camera.distortion[0], -100, 100},
      {"camera.k2", "", "radial distortion k2", &c.camera.distortion[1], -100, 100},
      {"camera.p1", "", "tangential distortion p1", &c.camera.distortion[2], -1, 1},
      {"camera.p2", "", "tangential distortion p2", &c.camera.distortion[3], -1, 1},
      {"camera.k3", "", "radial distortion k3", &c.camera.distortion[4], -100, 100},
      {"depth.units_per_m", "1/m", "raw uint16 depth value per metre (TUM 5000, OpenNI2 1 mm: 1000)", &c.depth.units_per_m, 1e-3, 1e6},
      {"depth.min_m", "m", "nearer depth is invalid (PrimeSense: nothing reliable below ~0.4 m)", &c.depth.min_m, 0.0, 100},
      {"depth.max_m", "m", "farther depth is invalid (beyond ~4.5 m sigma_Z exceeds 3 cm)", &c.depth.max_m, 0.01, 100},
      {"depth.edge_max_relative_step", "", "a keypoint whose 5x5 depth neighbourhood spans more than this fraction of its depth is on an occlusion edge: not used", &c.depth.edge_max_relative_step, 0.0, inf},
      {"depth.compensate_timing", "", "carry each keypoint's depth from the depth frame's capture time to the colour frame's", &c.depth.compensate_timing},
      {"depth.registration_x_px", "px", "the depth image's misregistration against the colour along x: what the colour shows at u is in the depth at u - this (bench/depth_lag_edges.py measures it)", &c.depth.registration_x_px, -50, 50},
      {"depth.registration_y_px", "px", "the same along y", &c.depth.registration_y_px, -50, 50},
      {"depth.lag_beyond_stamps_s", "s", "how much earlier than its stamps say (relative to its colour frame) a depth frame is taken: the motion along the optical axis is carried to the colour's instants by it (bench/depth_lag_edges.py measures it: its age less what the stamps show)", &c.depth.lag_beyond_stamps_s, -0.1, 0.1},
      {"depth.tilt_lag_beyond_stamps_s", "s", "how much earlier than the stamps the tilt rotations (about the image's x and y axes) are measured, the depth's lag leaking into them through the slide: each frame's tilt is carried to the stamps by it, its image shift kept; not where a gyro times the rotations", &c.depth.tilt_lag_beyond_stamps_s, -0.1, 0.1},
      {"features.detector", "", "GRID_ORB (ours) or an OpenCV detector by name: ORB, AKAZE, BRISK, SIFT, KAZE, FAST, GFTT, AGAST", &c.features.detector},
      {"features.descriptor", "", "GRID_ORB (with its detector) or an OpenCV descriptor: ORB, AKAZE, BRISK, SIFT, KAZE", &c.features.descriptor},
      {"features.max_features", "", "keypoints per frame", &c.features.max_features, 10, 100000},
      {"features.border_px", "px", "image periphery masked before detection (distortion is worst there)", &c.features.border_px, 0, 1000},
      {"features.orb_levels", "", "scale-pyramid levels", &c.features.orb_levels, 1, 16},
      {"features.orb_scale_factor", "", "scale between pyramid levels", &c.features.orb_scale_factor, 1.01, 2.0},
      {"features.fast_threshold", "", "FAST corner threshold (grey levels)", &c.features.fast_threshold, 1, 255},
      {"matching.ratio", "", "symmetric ratio test: best / second-best distance below this", &c.matching.ratio, 1e-6, 1.0},
      {"matching.window_px", "px", "half width of the search window around the motion prior's prediction; 0: every pair, as the paper", &c.matching.window_px, 0, 1e5},
      {"matching.subpixel_tracking", "", "move each matched keypoint to where the previous keypoint's patch lies, below a pixel; off: integer corners, as the paper", &c.matching.subpixel_tracking},
      {"ransac.inlier_threshold_m", "m", "lambda_inlier: 3-D distance of an inlier", &c.ransac.inlier_threshold_m, 1e-5, 10},
      {"ransac.max_iterations", "", "RANSAC hypotheses at most", &c.ransac.max_iterations, 1, 1000000},
      {"ransac.refine_threshold", "", "refit with the threshold min(3 sigma_inliers, lambda_inlier)", &c.ransac.refine_threshold},
      {"ransac.min_inliers", "", "fewer inliers and the pair is reported failed", &c.ransac.min_inliers, 3, 1000000},
      {"ransac.adaptive_stop", "", "stop once an all-inlier sample was drawn with 99.9 % probability", &c.ransac.adaptive_stop},
      {"covariance.perturbations", "", "perturbed refits the 6x6 covariance is estimated from", &c.covariance.perturbations, 8, 100000},
      {"covariance.model", "", "physical (pipeline/noise_model.hpp) or paper (Willis & Brink eq. 2 alone)", &c.covariance.model},
      {"covariance.depth_noise_coeff", "1/m", "axial depth noise sigma_Z = coeff Z^2", &c.covariance.depth_noise_coeff, 1e-9, 1.0},
      {"covariance.depth_lateral_sigma_px", "px", "lateral noise of the depth map", &c.covariance.depth_lateral_sigma_px, 0.0, 100},
      {"covariance.timing_sigma_s", "s", "colour-to-depth capture-time offset error; < 0: estimated from the stamps' jitter", &c.covariance.timing_sigma_s, -1, 1},
      {"covariance.resample_cell_px", "px", "each perturbation resamples the inliers by image cells this size; 0: none", &c.covariance.resample_cell_px, 0, 1e5},
      {"covariance.colour_latency_sigma_s", "s", "colour capture latency behind its stamps the stamps do not show; 0: calibrated away", &c.covariance.colour_latency_sigma_s, 0, 1},
      {"covariance.depth_latency_sigma_s", "s", "depth capture latency behind the colour; 0: calibrated away", &c.covariance.depth_latency_sigma_s, 0, 1},
      {"covariance.integration_window_s", "s", "a consumer summing motions over this horizon stays covered against the latencies; 0: per pair only", &c.covariance.integration_window_s, 0, 3600},
      {"covariance.pixel_sigma_px", "px", "keypoint localisation error at full resolution (integer corners: 1/sqrt(12))", &c.covariance.pixel_sigma_px, 0.0, 100, true},  // 0: singular fit weights
      {"covariance.residual_variance_factor", "", "scale the noise by the fit's a-posteriori variance factor", &c.covariance.residual_variance_factor},
      {"covariance.scale", "", "multiplies the reported covariance; 1: the noise model as it stands", &c.covariance.scale, 1e-6, 1e6},
      {"covariance.smoothing_s", "s", "the reported covariance is the running log-Euclidean mean of the pairs' rate covariances over this time; 0: each pair's own", &c.covariance.smoothing_s, 0, 3600},
      {"covariance.smoothing_pass_ratio", "", "where a pair's own covariance is wider than the running mean, it weighs in from sqrt(this) times as wide (variance) and goes out as its own from this; 0: never", &c.covariance.smoothing_pass_ratio, 0, 1e6},
      {"refinement.enabled", "", "refine the feature motion by aligning the two depth maps and fuse the two by information", &c.refinement.enabled},
      {"refinement.stride_px", "px", "the depth maps are sampled every this many pixels for the alignment", &c.refinement.stride_px, 2, 64},
      {"refinement.average_depth", "", "each sample of the depth maps is the mean of the 5x5 pixels around it where they lie on one surface (spanning at most twice depth.edge_max_relative_step); off: its one pixel", &c.refinement.average_depth},
      {"refinement.iterations", "", "Gauss-Newton steps of the depth alignment at most", &c.refinement.iterations, 1, 100},
      {"refinement.max_distance_m", "m", "a depth point further than this from its associated point is not used", &c.refinement.max_distance_m, 1e-4, 10, true},
      {"refinement.min_points", "", "fewer associated depth points and the feature motion stands alone", &c.refinement.min_points, 10, 1000000},
      {"refinement.cell_px", "px", "image cells whose residuals may be correlated: the alignment covariance's clusters", &c.refinement.cell_px, 8, 1e5},
      {"refinement.sigma_scale_prior", "", "the depth alignment's sigma is scaled by factors learnt against the features; their start", &c.refinement.sigma_scale_prior, 1, 1e6},
      {"refinement.sigma_scale_rate", "", "how far one pair may move those factors (share per pair)", &c.refinement.sigma_scale_rate, 0, 0.5},
      {"refinement.sigma_scale_max", "", "the factors' ceiling: beyond it the sensor's depth adds nothing", &c.refinement.sigma_scale_max, 1, 1e9},
      {"refinement.max_sigma_scale_fused", "", "the alignment is fused only while both learnt factors are at most this: beyond, its errors are ones its residuals cannot see", &c.refinement.max_sigma_scale_fused, 1, 1e9},
      {"refinement.max_depth_lag_s", "s", "the depth's capture lag behind the colour, learnt from the depth alignment against the features and reported, at most this much", &c.refinement.max_depth_lag_s, 0, 1},
      {"refinement.max_depth_lag_fused_s", "s", "the alignment is fused only while the depth's learnt lag behind the colour is at most this either way: a depth taken at another instant measures another motion", &c.refinement.max_depth_lag_fused_s, 0, 1},
      {"refinement.distrusted_sigma_scale", "", "where the learnt factors or lag refuse fusion, the alignment is fused with its sigma in sideways translation scaled by this fixed factor instead; 0: the features stand alone", &c.refinement.distrusted_sigma_scale, 0, 1e6},
      {"refinement.distrusted_sigma_scale_optical_axis", "", "the same for its translation along the optical axis, which the depth's lag and distortion move most", &c.refinement.distrusted_sigma_scale_optical_axis, 1, 1e6},
      {"refinement.distrusted_sigma_scale_rotation", "", "the same for its rotation", &c.refinement.distrusted_sigma_scale_rotation, 1, 1e6},
      {"keyframes.enabled", "", "measure each frame against a kept keyframe too, so that the pose over one view does not walk; off: frame to frame only", &c.keyframes.enabled},
      {"keyframes.kept", "", "recent keyframes kept, so that a return to an earlier view re-attaches to it", &c.keyframes.kept, 1, 64},
      {"keyframes.min_inlier_share", "", "a new keyframe once the inliers against the current one fall below this share of its first frame's", &c.keyframes.min_inlier_share, 0.0, 1.0},
      {"keyframes.gain", "", "the share of the keyframe's disagreement with the frame pairs' prediction taken per frame: the pose is pulled back to the keyframe over about 1/gain frames", &c.keyframes.gain, 0.0, 1.0},
      {"latency.enabled", "", "measure when the frames were taken against the autopilot's gyro (live: its ATTITUDE; replay: imu.txt or --imu) and stamp every motion then", &c.latency.enabled},
      {"latency.min_s", "s", "the latencies searched (stamp minus capture instant, on the gyro's clock): from", &c.latency.min_s, -1, 1},
      {"latency.max_s", "s", "to", &c.latency.max_s, -1, 1},
      {"latency.memory_s", "s", "a moving camera's evidence fades over this long, so a slowly changing latency is followed; at rest nothing fades", &c.latency.memory_s, 1, 1e6},
      {"latency.converged_sigma_s", "s", "applied once known to this standard error", &c.latency.converged_sigma_s, 1e-5, 1, true},
      {"latency.max_slew", "s/s", "the applied latency moves towards the estimate at most this fast (seconds per second of frames)", &c.latency.max_slew, 1e-4, 0.5},
      {"latency.mount_warning_deg", "deg", "a camera mount measured against the gyro further than this from body.* is warned about", &c.latency.mount_warning_deg, 0.1, 180},
      {"latency.retime_image_shift", "", "move the image shift (sideways translation) to the capture instants where the colour image's own latency is told apart from the depth's", &c.latency.retime_image_shift},
  });
}

void add_seed_setting(PipelineConfig& c, SettingsTable& table) {
  table.insert(table.end(), {
      {"seed", "", "seeds RANSAC and the perturbations with each pair's content: the same frames, the same result", &c.seed, 0, 2147483647},  // a file's integers are 32-bit (OpenCV's reader)
  });
}

void validate_pipeline(const PipelineConfig& c) {
  if (c.depth.min_m >= c.depth.max_m)
    throw ConfigError("config key 'depth.min_m': must be below depth.max_m");
  if (c.camera.cx >= c.camera.width || c.camera.cy >= c.camera.height)
    throw ConfigError("config key 'camera.cx': principal point lies outside the image");
  if (2 * c.features.border_px >= std::min(c.camera.width, c.camera.height))
    throw ConfigError("config key 'features.border_px': the border leaves no image");
  if (!listed(kCovarianceModels, c.covariance.model))
    throw ConfigError("config key 'covariance.model': unknown model '" + c.covariance.model + "' (" +
                      joined(kCovarianceModels) + ")");
  if (!listed(kFeatureDetectors, c.features.detector))
    throw ConfigError("config key 'features.detector': unknown detector '" + c.features.detector + "' (" +
                      joined(kFeatureDetectors) + ")");
  if (!listed(kFeatureDescriptors, c.features.descriptor))
    throw ConfigError("config key 'features.descriptor': unknown descriptor '" + c.features.descriptor + "' (" +
                      joined(kFeatureDescriptors) + ")");
  if ((c.features.descriptor == kGridOrb) != (c.features.detector == kGridOrb))
    throw ConfigError("config key 'features.descriptor': GRID_ORB is a detector and descriptor in one: set both");
  if ((c.features.descriptor == "AKAZE") != (c.features.detector == "AKAZE") ||
      (c.features.descriptor == "KAZE") != (c.features.detector == "KAZE"))
    throw ConfigError("config key 'features.descriptor': " + c.features.descriptor +
                      " descriptors need the matching (A)KAZE detector");
  if (c.refinement.stride_px * 4 > std::min(c.camera.width, c.camera.height))
    throw ConfigError("config key 'refinement.stride_px': fewer than 4 grid rows in the image");
  if (c.ransac.min_inliers < 3)
    throw ConfigError("config key 'ransac.min_inliers': a rigid motion needs at least 3");
  if (c.latency.max_s - c.latency.min_s < 0.01)
    throw ConfigError("config key 'latency.max_s': must be at least 10 ms above latency.min_s");
}

}  // namespace rgbdo
