#pragma once
// Stage 5b: the feature motion refined by the depth maps themselves.
//
// The features measure a motion from a few hundred points, each one pixel's depth at an
// integer corner; the depth maps hold thousands of surface points the features throw away.
// Here the current frame's depth, on a coarse grid (`refinement.stride_px`), is aligned to the
// previous frame's surface by point-to-plane Gauss-Newton with projective association
// (Chen & Medioni 1991; KinectFusion's data association), started at the feature motion.
//
// Its covariance comes from the alignment's own residuals, not from a sensor model: the
// cluster-robust ("sandwich") covariance H^-1 (sum_c g_c g_c^T) H^-1 over image cells, g_c the
// cell's gradient at the solution, which covers residuals correlated within a cell and noise of
// any size, plus (6 / cells) s^2 H^-1 so that few cells cannot leave a direction without
// variance. A direction the surfaces leave free (a plane's sliding) is left out altogether.
// What the residuals cannot see (an error the whole depth map shares) is learnt against the
// features (AlignmentTrust), and the two estimates are fused by information where they agree
// (fuse_estimates): where the depth is exact (a rendered or a good stereo sensor) the
// alignment dominates, where it is noisy (Kinect v1) the features keep most of the weight.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "rgbd_odometry/pipeline/pipeline_config.hpp"
#include "rgbd_odometry/core/geometry.hpp"
#include "rgbd_odometry/pipeline/learnt_constant.hpp"
#include "rgbd_odometry/simd/kernels.hpp"

namespace rgbdo {

// One frame's depth on the coarse grid: points (camera frame, metres) and the surface normals
// at them; z = 0 marks no point, a zero normal no normal (a hole or a depth edge nearby).
struct DepthCloud {
  int cols = 0, rows = 0;
  std::vector<Eigen::Vector3f> point;   // on the sample's ray at its depth (averaged with refinement.average_depth); zero: none
  std::vector<Eigen::Vector3f> normal;
  std::vector<float> raw_depth;         // the sample's own pixel, unaveraged (what a keypoint reads)
  std::vector<float> averaged;          // DepthCloudBuilder's scratch: the averaged samples' means
  void clear();
  bool empty() const { return cols == 0; }
};

class DepthCloudBuilder {
 public:
  DepthCloudBuilder(const CameraConfig& camera, const DepthConfig& depth, const RefinementConfig& refinement);
  // Samples depth_m (CV_32FC1, metres, 0 = none) on a grid every stride_px pixels of the
  // undistorted image, each sample averaged on its surface (refinement.average_depth);
  // allocates only the first time.
  void build(const cv::Mat& depth_m, DepthCloud& out) const;

 private:
  int stride_, cols_, rows_, width_, height_;
  DepthConfig depth_;
  // The samples averaged (refinement.average_depth): their indices, and their pixels, whose 5x5
  // window lies inside the image.
  std::vector<int> averaged_sample_;
  std::vector<std::int32_t> averaged_pixel_;
  std::vector<int> pixel_;            // the sensor pixel each grid sample reads (-1: outside the image)
  std::vector<Eigen::Vector2f> ray_;  // that pixel's undistorted (x/z, y/z)
};

struct DepthAlignment {
  bool ok = false;
  Eigen::Isometry3d T_prev_curr = Eigen::Isometry3d::Identity();
  // The directions of motion the surfaces constrain (the first `constrained` columns, an
  // orthonormal basis of the right perturbation), and the covariance within them. A plane
  // leaves its sliding directions out: there the alignment knows nothing, however small its
  // residuals.
  Matrix6d basis = Matrix6d::Identity();
  int constrained = 0;
  Matrix6d covariance = Matrix6d::Zero();  // of the right perturbation of T_prev_curr, within the basis
  int points = 0;                          // associations used in the last iteration
  // This pair's depth noise coefficient c (sigma_Z = c Z^2 along each ray), read from the
  // residuals at the solution net of the depth's rounding; 0 when they are rounding alone,
  // negative when the alignment failed.
  double depth_noise_coeff = -1;
};

// The camera's intrinsics on the alignment's grid of stride_px pixels (DepthCloudBuilder's
// pinhole grid), as the association kernel takes them: {fx, fy, cx, cy}, cx and cy with + 0.5
// so that truncation rounds to the nearest sample.
std::array<float, 4> grid_intrinsics(const CameraConfig& camera, int stride_px);

class DepthAligner {
 public:
  DepthAligner(const CameraConfig& camera, const RefinementConfig& refinement, double depth_noise_coeff,
               double depth_units_per_m);
  // Aligns curr's points to prev's surface, starting at `seed`.
  void align(const DepthCloud& prev, const DepthCloud& curr, const Eigen::Isometry3d& seed, DepthAlignment& out);

 private:
  RefinementConfig config_;
  double depth_noise_coeff_;
  double quantum_sigma_m_;  // one depth unit's rounding, 1/sqrt(12) of it
  std::array<float, 4> grid_;  // grid_intrinsics()

  // One Gauss-Newton step's sums at the current associations.
  struct NormalEquations {
    Matrix6d H = Matrix6d::Zero();
    Vector6d b = Vector6d::Zero();
    double s2 = 0;  // the a-posteriori variance factor
    int used = 0;   // associations with weight
    double cutoff2 = 0, floor_r2 = 0;  // the robust weights' scale: see robust_share()
  };
  // An association's robust weight, Tukey's share of its own (0: none), and its weight in those sums.
  static double robust_share(const simd::Association& term, const NormalEquations& eq);
  static float term_weight(const simd::Association& term, const NormalEquations& eq);
  // The steps of align(): the associations at T (terms_, term_cells_; `it` the iteration), the
  // robustly weighted sums over them (with kCells, each cell's gradient too; sum_cells() adds
  // those to sums made without), the covariance from them.
  void associate(const DepthCloud& curr, const Eigen::Isometry3d& T, int it, simd::AssociateInput& in);
  template <bool kCells>
  NormalEquations weighted_normal_equations();
  void sum_cells(const NormalEquations& eq);
  // c from the residuals at T: their median, net of rounding, against each association's
  // noise geometry (both depths along their rays, seen along the normal).
  double residual_noise_coeff(const DepthCloud& prev, const DepthCloud& curr, const Eigen::Isometry3d& T);
  // H_inv: H's pseudo-inverse within the directions the surfaces constrain.
  bool cluster_covariance(const NormalEquations& eq, DepthAlignment& out, Matrix6d& H_inv) const;
  // Adds to out.covariance what the rounding errors shared by samples read as one depth unit
  // do to the estimate; shared_rounding_spread is their spread over every `every`-th of the
  // last sums' associations (to go between H^-1 and H^-1).
  void add_shared_rounding(const DepthCloud& prev, const DepthCloud& curr, const NormalEquations& eq,
                           const Matrix6d& H_inv, DepthAlignment& out);
  Matrix6d shared_rounding_spread(const DepthCloud& prev, const DepthCloud& curr, const NormalEquations& eq, int every);

  simd::AssociateFn associate_;  // the active kernel set's
  // The associations at the last linearisation (the first term_count_) and each one's image cell.
  std::vector<simd::Association> terms_;
  std::vector<int> term_cells_;
  size_t term_count_ = 0;
  std::vector<float> scaled_;
  std::vector<Vector6d> cell_gradient_;
  std::vector<int> cell_count_;
  int cell_grid_ = 1, cells_x_ = 1;  // grid samples a cell, cells a row
  double units_per_m_;
  // Each depth unit's summed gradient (shared_rounding_spread), hashed, for prev's readings and
  // curr's; a bucket counts only while its mark is the current reading's generation.
  std::vector<Eigen::Matrix<float, 6, 1>> unit_gradient_prev_, unit_gradient_curr_;
  std::vector<std::uint32_t> unit_mark_prev_, unit_mark_curr_;
  std::uint32_t unit_generation_ = 0;
  std::vector<int> shared_prev_, shared_curr_;  // the buckets read more than once
};

// How far the depth alignment's own covariance may be trusted on this sensor, learnt online
// from its disagreement with the features. The alignment's residuals cannot see an error a
// depth map shares across the whole image (a structured-light sensor's distortion pattern, a
// depth latency the stamps do not show): on TUM fr1's Kinect its errors are 5-20 times its own
// sigma, on exact depth they are not. So its covariance is scaled by k_t^2 in translation and
// k_r^2 in rotation, each factor nudged after every pair so that the difference d between the
// two estimates has its expected size under C_features + K C_depth K (3 per 3-D block). An
// exact sensor drives k to its floor of 1 and the alignment dominates; a noisy one is weighted
// as it turns out to be. Starts at the prior, changes by at most the rate's share per pair.
class AlignmentTrust {
 public:
  explicit AlignmentTrust(const RefinementConfig& config);
  // C_depth scaled: K C K with K = diag(k_t, k_t, k_t, k_r, k_r, k_r).
  Matrix6d scaled(const Matrix6d& depth_cov) const;
  // One pair: d = depth (-) features (right perturbation), both covariances as fused.
  // lag_rotation_cov: what the depth's lag adds to the alignment's rotation (DepthLagEstimate).
  void update(const Vector6d& d, const Matrix6d& feature_cov, const Matrix6d& depth_cov,
              const Eigen::Matrix3d& lag_rotation_cov);
  double translation_scale() const { return k_t_; }
  double rotation_scale() const { return k_r_; }

 private:
  // The last kWindow pairs' differences and covariances: errors that do not cancel from one
  // pair to the next show in their sum before they show in any one pair.
  static constexpr int kWindow = 15;
  struct Entry {
    Vector6d d;
    Matrix6d feature_cov, depth_cov;
  };
  std::array<Entry, kWindow> window_{};
  int filled_ = 0, next_ = 0;
  double k_t_, k_r_, rate_, max_;
};

// The depth's capture lag behind the colour that the stamps do not show, learnt from the two
// estimates. The features' rotation is the colour's (bearings); the depth alignment's motion
// is the depth's, over an interval earlier by the lag L, so that to first order
//     d_rot = depth (-) features = -L (w(t_curr) - w(t_prev)),
// the change of angular rate between the pair's frames (the previous pair's rate to this
// one's). L is the least-squares slope over the pairs seen (forgetting over about
// kLagMemoryPairs), with the rate changes' own noise taken out of the denominator (errors in
// the regressor would shrink L towards 0), started at 0 with the weight of a few pairs and
// bounded by refinement.max_depth_lag_s. On TUM fr1's Kinect it comes to 20-40 ms (the motion
// capture says 25-28 ms); on a synchronised sensor it stays near 0. The lag is not corrected
// pair by pair (the rate change it would multiply is the features' own, as noisy as the
// correction is large); the alignment's rotation is weighted by what it may do instead.
class DepthLagEstimate {
 public:
  explicit DepthLagEstimate(const RefinementConfig& config);
  double lag_s() const { return lag_s_; }
  // What the lag does to the alignment's rotation, as a covariance: L^2 times the typical
  // change of angular rate between frames (its running second moment, less its noise).
  Eigen::Matrix3d rotation_covariance() const;
  // d_rotation: rotation part of depth (-) features; delta_rate: the change of angular rate
  // (rad/s); its noise variance summed over the axes.
  void update(const Eigen::Vector3d& d_rotation, const Eigen::Vector3d& delta_rate, double delta_rate_variance);

 private:
  double sum_dr_ = 0, sum_rr_ = 0;  // sum of d . delta and of |delta|^2 - noise, forgetting
  Eigen::Matrix3d moment_ = Eigen::Matrix3d::Zero();  // running mean of delta delta^T - noise
  double lag_s_ = 0, max_s_;
};

// The sensor's depth noise coefficient c (sigma_Z = c Z^2), learnt online from the depth
// alignment's residuals (DepthAlignment::depth_noise_coeff) by learnt_constant.hpp's rule:
// started at the configured prior (covariance.depth_noise_coeff, the Kinect's), the first ten
// readings averaged with it geometrically (a sensor's c may lie a decade or two below the
// Kinect's: ICL's 6e-5, which 10 % a pair took 30 pairs to reach), then each moving it by at
// most kNoiseRate of itself; kept within [kNoiseMin, kNoiseMax] /m. The residuals of two
// consecutive frames see the noise of both and any error the pair's depth maps do not share
// (a structured-light sensor's distortion pattern moving with the camera): on such a sensor
// it reads high, never low.
class DepthNoiseEstimate {
 public:
  static constexpr double kNoiseRate = 0.1, kNoiseMin = 1e-5, kNoiseMax = 1e-2;
  explicit DepthNoiseEstimate(double prior);
  void update(double pair_coeff) { c_.add(pair_coeff); }
  double coeff() const { return c_.value(); }

 private:
  LearntConstant c_;
};

// Fuses a full estimate `a` of one motion with an estimate `b` of its components along the
// first k columns of `basis_b` (orthonormal), each with the covariance of its right
// perturbation: the information-weighted mean about `a` and the fused covariance. False
// (outputs untouched) when they disagree beyond the chi^2(k) 99.9 % gate.
// b_error_cov, when given: b's error as it is, where cov_b weighs b down on purpose (errors
// that do not average out over a consumer's second); the fused covariance is then that of the
// estimate made with cov_b's weights, (I - G) cov_a (I - G)^T + G b_error_cov G^T (G the gain
// taken to the full space), not the smaller one cov_b's information alone would claim.
bool fuse_estimates(const Eigen::Isometry3d& a, const Matrix6d& cov_a, const Eigen::Isometry3d& b,
                    const Matrix6d& cov_b, const Matrix6d& basis_b, int k, Eigen::Isometry3d& fused,
                    Matrix6d& fused_cov, const Matrix6d* b_error_cov = nullptr);

}  // namespace rgbdo
