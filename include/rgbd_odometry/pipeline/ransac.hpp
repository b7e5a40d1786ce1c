#pragma once
// Stage 4: robust rigid motion from 3-D correspondences (Willis & Brink Sec. III-A, stage 2).
// Hypotheses from random 3-point samples are scored by their inlier count at lambda_inlier;
// the best is then refined as PCL's refineModel does: fit all inliers by least squares,
// shrink the threshold to min(3 sigma_inliers, lambda_inlier), re-select, until stable.
// The final fit minimises the Mahalanobis residual under the ray-aligned sensor noise
// (noise_model.hpp): depth errors along the viewing ray are cheap, lateral ones are not. Its
// weights are each point's own covariance where the caller gives them (the depth's slope at
// the keypoint and the keypoint's level in), so that they stay finite and right when the
// sensor's depth noise is near zero; a pair whose Mahalanobis residual exceeds the chi^2(3)
// 99 % point is then weighed down as Huber's loss does. Without that, a model that calls the
// depth exact lets the few keypoints where it is not (corners) steer the fit: ICL-NUIM told its
// true constants, 2.34 mm pair RPE against 0.35 mm with it
// (src/pipeline/MEASUREMENTS.md#huber-weights-where-the-model-is-wrong).
//
// Allocation-free: every buffer is sized at construction for `capacity` correspondences
// (more only on the first larger input), the caller's RansacResult keeps its inlier buffer
// across frames. A sample's motion comes from the closed-form triplet fit (fit_triplet: no
// SVD); hypotheses are scored by the active SIMD kernel (rgbd_odometry/simd/score.hpp) over
// structure-of-arrays float coordinates. The refinement and final fits run in double.
#include <Eigen/Geometry>
#include <vector>

#include "rgbd_odometry/simd/kernels.hpp"
#include "rgbd_odometry/pipeline/pipeline_config.hpp"
#include "rgbd_odometry/pipeline/noise_model.hpp"
#include "rgbd_odometry/core/rng.hpp"
#include "rgbd_odometry/core/status.hpp"

namespace rgbdo {

struct RansacResult {
  Status status = Status::RansacFailed;
  Eigen::Isometry3d T_prev_curr = Eigen::Isometry3d::Identity();  // maps curr points into prev
  std::vector<int> inliers;  // indices into the point pairs; capacity reused across calls
  double threshold_m = 0;    // the final (refined) inlier threshold
  int hypotheses = 0;        // non-degenerate samples scored
};

// Each point pair's two 3x3 covariances (noise_model.hpp), in the pairs' order.
struct PointPairCovariances {
  std::vector<Eigen::Matrix3d> prev, curr;
};

// How many hypotheses make drawing at least one all-inlier sample 99.9 % likely when the best
// so far has `inliers` of `pairs`: 1 when all are inliers, `cap` when none is (or the count
// would exceed it).
int adaptive_hypotheses(int inliers, int pairs, int cap);

// Draws a 3-point sample of the pairs (three calls of rng.below): false when it cannot give a
// motion worth scoring (an index repeated, a side shorter than 2 cm or a triangle flatter than
// ~6 degrees in either cloud, a side whose length the two clouds disagree on by more than twice
// the inlier threshold: a rigid motion keeps distances); else its points, s of curr, d of prev.
bool draw_sample(Rng& rng, const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                 double inlier_threshold_m, Eigen::Vector3d s[3], Eigen::Vector3d d[3]);

class RigidRansac {
 public:
  RigidRansac(const RansacConfig& ransac, const SensorNoise& noise, int capacity);

  // prev[k] ~ T * curr[k] for inliers k. `out` is overwritten. Without `covariances` the
  // final fit weighs each point by point_covariance().
  void estimate(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr, Rng& rng,
                RansacResult& out, const PointPairCovariances* covariances = nullptr);

  // The hypothesis stage alone: best motion of up to max_iterations non-degenerate samples;
  // returns how many were scored (0: every draw was degenerate).
  int sample_hypotheses(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr, Rng& rng,
                        Eigen::Isometry3d& best);

  // The refinement alone, from a given motion (used again after the points were corrected).
  void refine(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
              const Eigen::Isometry3d& initial, RansacResult& out, const PointPairCovariances* covariances = nullptr);

 private:
  void load(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr);  // into the SoA
  void select_inliers(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                      const Eigen::Isometry3d& T, double threshold, std::vector<int>& out) const;
  // Gauss-Newton on sum_k r_k^T (C_prev + R C_curr R^T)^-1 r_k over the inliers, from T.
  Eigen::Isometry3d fit_anisotropic(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                                    const std::vector<int>& inliers, const PointPairCovariances* covariances,
                                    Eigen::Isometry3d T) const;
  RansacConfig config_;
  SensorNoise noise_;
  simd::ScoreRigidFn score_;
  std::vector<float> px_, py_, pz_, cx_, cy_, cz_;  // prev and curr, structure of arrays
  std::vector<int> scratch_inliers_;
  std::vector<Eigen::Vector3d> fit_prev_, fit_curr_;
  std::vector<double> fit_weights_;
};

}  // namespace rgbdo
