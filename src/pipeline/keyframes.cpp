#include "rgbd_odometry/pipeline/keyframes.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>

#include "rgbd_odometry/core/clock.hpp"
#include "rgbd_odometry/core/cost_stage.hpp"
#include "rgbd_odometry/pipeline/depth_alignment.hpp"
#include "rgbd_odometry/pipeline/depth_clock.hpp"
#include "rgbd_odometry/pipeline/grid_orb.hpp"

namespace rgbdo {
namespace {

// A kept keyframe is tried for a return when at least this share of its points lies in view.
constexpr double kMinReturnOverlap = 0.5;

Eigen::Isometry3d orthonormalised(Eigen::Isometry3d T) {
  T.linear() = Eigen::Quaterniond(T.linear()).normalized().toRotationMatrix();
  return T;
}

// The larger of two covariances in every direction: in floor's whitened coordinates, every
// eigenvalue of cov below 1 raised to 1 (cov itself where floor is not positive definite).
Matrix6d raised_to(const Matrix6d& cov, const Matrix6d& floor) {
  const Eigen::SelfAdjointEigenSolver<Matrix6d> model(floor);
  if (model.info() != Eigen::Success || !(model.eigenvalues().minCoeff() > 0)) return cov;
  const Matrix6d root = model.operatorSqrt(), root_inv = model.operatorInverseSqrt();
  const Eigen::SelfAdjointEigenSolver<Matrix6d> whitened(root_inv * cov * root_inv);
  if (whitened.info() != Eigen::Success) return cov;
  const Vector6d raised = whitened.eigenvalues().cwiseMax(1.0);
  Matrix6d out = root * whitened.eigenvectors() * raised.asDiagonal() * whitened.eigenvectors().transpose() * root;
  return 0.5 * (out + out.transpose());
}

}  // namespace

void anchored_points(const KeypointGeometry& geometry, const FrameTimes& times, const MotionPrior* motion,
                     double fx, double fy, std::vector<Eigen::Vector3d>& out) {
  const double offset_s = static_cast<double>(times.t_colour_ns - times.t_depth_ns) * 1e-9;
  out.resize(geometry.depth_m.size());
  for (size_t i = 0; i < out.size(); ++i) {
    const double z = geometry.depth_m[i];
    const Eigen::Vector2d& xn = geometry.normalized[i];
    if (!(z > 0)) {
      out[i].setZero();
      continue;
    }
    const Eigen::Vector3d p(xn.x() * z, xn.y() * z, z);
    double zc = z;
    if (motion != nullptr && offset_s != 0)
      zc = depth_at_colour_instant(z, p, geometry.depth_gradient[i], static_pixel_velocity(p, *motion, fx, fy),
                                   offset_s, *motion);
    out[i] = zc > 0 ? Eigen::Vector3d(xn.x() * zc, xn.y() * zc, zc) : Eigen::Vector3d::Zero();
  }
}

Matrix6d rigid_fit_covariance(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                              const std::vector<int>& inliers, const PointPairCovariances& covariances,
                              std::span<const int> cells, const Eigen::Isometry3d& T) {
  const Eigen::Matrix3d R = T.linear();
  Matrix6d information = Matrix6d::Zero();
  double chi2 = 0;
  // Each cell's score, sum of J^T W r over its pairs (cells are few: at most kMaxCells).
  constexpr size_t kMaxCells = 256;
  std::array<Vector6d, kMaxCells> score;
  std::array<bool, kMaxCells> used{};
  for (int k : inliers) {
    const auto i = static_cast<size_t>(k);
    const Eigen::Matrix3d W = (covariances.prev[i] + R * covariances.curr[i] * R.transpose()).inverse();
    // r = prev - T Exp(delta) curr: d r / d rho = -R, d r / d phi = R [curr]x.
    Eigen::Matrix<double, 3, 6> J;
    J.leftCols<3>() = -R;
    J.rightCols<3>() = R * skew(curr[i]);
    information += J.transpose() * W * J;
    const Eigen::Vector3d r = prev[i] - T * curr[i];
    chi2 += r.dot(W * r);
    if (!cells.empty()) {
      const auto c = static_cast<size_t>(std::clamp(cells[i], 0, static_cast<int>(kMaxCells) - 1));
      if (!used[c]) score[c].setZero();
      used[c] = true;
      score[c] += J.transpose() * (W * r);
    }
  }
  const Eigen::LDLT<Matrix6d> ldlt(information);
  const double dof = 3.0 * static_cast<double>(inliers.size()) - 6;
  const double variance_factor = dof > 0 ? std::max(1.0, chi2 / dof) : 1.0;
  Matrix6d cov = variance_factor * ldlt.solve(Matrix6d::Identity());
  cov = 0.5 * (cov + cov.transpose());
  // Errors shared by the points of a region (a structured-light sensor's depth distortion,
  // which frame to frame cancels but against a keyframe seen from elsewhere does not) are not
  // in the model: the residuals' scatter between cells shows them. The cluster-robust
  // ("sandwich") covariance H^-1 (sum_c s_c s_c^T) H^-1, with the small-sample factor
  // C / (C - 1), is taken wherever it exceeds the model's.
  int clusters = 0;
  Matrix6d meat = Matrix6d::Zero();
  for (size_t c = 0; c < kMaxCells; ++c)
    if (used[c]) {
      meat += score[c] * score[c].transpose();
      ++clusters;
    }
  if (clusters < 2) return cov;
  meat *= static_cast<double>(clusters) / (clusters - 1);
  const Matrix6d H_inv = ldlt.solve(Matrix6d::Identity());
  Matrix6d sandwich = H_inv * meat * H_inv;
  sandwich = 0.5 * (sandwich + sandwich.transpose());
  return raised_to(sandwich, cov);
}

KeyframeTracker::KeyframeTracker(const PipelineConfig& config)
    : config_(config),
      noise_(sensor_noise(config)),
      tracking_(tracks_keypoints(config)),
      matcher_(config.matching.ratio),
      tracker_(config.camera, config.features.orb_scale_factor, config.features.max_features),
      ransac_(config.ransac, sensor_noise(config), config.features.max_features),
      aligner_(config.camera, config.refinement, config.covariance.depth_noise_coeff, config.depth.units_per_m) {
  const auto capacity = static_cast<size_t>(config.features.max_features);
  matcher_.reserve(config.features.max_features);
  for (auto* v : {&curr_points_, &pair_kf_, &pair_curr_, &tracked_points_}) v->reserve(capacity);
  usable_.reserve(capacity);
  predicted_.reserve(capacity);
  matches_.reserve(capacity);
  pair_covariances_.prev.reserve(capacity);
  pair_covariances_.curr.reserve(capacity);
  pair_cells_.reserve(capacity);
  fit_.inliers.reserve(capacity);
  kept_.resize(static_cast<size_t>(config.keyframes.kept));
  const int grid_points = (config.camera.width / config.refinement.stride_px + 1) *
                          (config.camera.height / config.refinement.stride_px + 1);
  for (Keyframe& kf : kept_) {
    kf.features.keypoints.reserve(capacity);
    for (auto* v : {&kf.geometry.normalized, &kf.geometry.pixel, &kf.geometry.depth_gradient}) v->reserve(capacity);
    kf.geometry.depth_m.reserve(capacity);
    kf.points.reserve(capacity);
    kf.levels.reserve(capacity);
    if (config.features.descriptor == kGridOrb)
      kf.features.descriptor_storage.create(config.features.max_features, GridOrbExtractor::kDescriptorBits / 8, CV_8UC1);
    if (tracking_) kf.gray.create(config.camera.height, config.camera.width, CV_8UC1);
    if (config.refinement.enabled) {
      kf.cloud.point.reserve(static_cast<size_t>(grid_points));
      kf.cloud.normal.reserve(static_cast<size_t>(grid_points));
      kf.cloud.raw_depth.reserve(static_cast<size_t>(grid_points));
      kf.cloud.averaged.reserve(static_cast<size_t>(grid_points));
    }
  }
}

Matrix6d KeyframeTracker::extended(const Matrix6d& chain, const Matrix6d& step) {
  const double tc = chain.trace(), ts = step.trace();
  if (!(tc > 0 && ts > 0)) return chain + step;
  const double a = std::sqrt(ts / tc);
  return (1 + a) * chain + (1 + 1 / a) * step;
}

bool KeyframeTracker::agree(const Eigen::Isometry3d& T_pred, const Matrix6d& cov_pred, const Measurement& z) const {
  Eigen::Isometry3d fused;
  Matrix6d fused_cov;
  return fuse_estimates(T_pred, cov_pred, z.T, z.covariance, Matrix6d::Identity(), 6, fused, fused_cov);
}

void KeyframeTracker::correct(const Eigen::Isometry3d& T_pred, const Matrix6d& cov_pred, const Measurement& z) {
  const double g = config_.keyframes.gain;
  T_kf_curr_ = orthonormalised(T_pred * transform_from_xi(g * right_perturbation_between(T_pred, z.T)));
  cov_kf_curr_ = (1 - g) * cov_pred + g * z.covariance;
}

bool KeyframeTracker::holds(const Keyframe& kf, int inliers) const {
  const double floor = std::max(2.0 * config_.ransac.min_inliers, config_.keyframes.min_inlier_share * kf.reference_inliers);
  return inliers >= floor;
}

bool KeyframeTracker::measure(const Keyframe& kf, const ProcessedFrame& curr, const Eigen::Isometry3d& T_pred,
                              Measurement& out) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Eigen::Isometry3d curr_from_kf = T_pred.inverse();
  const bool windowed = config_.matching.window_px > 0 && kf.features.descriptors.type() == CV_8UC1 &&
                        curr.features.descriptors.type() == CV_8UC1;
  if (windowed) {
    predicted_.resize(kf.points.size());
    for (size_t i = 0; i < kf.points.size(); ++i) {
      const Eigen::Vector3d q = curr_from_kf * kf.points[i];
      predicted_[i] = kf.points[i].z() > 0 && q.z() > 0 ? Eigen::Vector2d(q.head<2>() / q.z()) : Eigen::Vector2d(nan, nan);
    }
    matcher_.match_within(kf.features.descriptors, curr.features.descriptors, predicted_, curr.geometry.normalized,
                          config_.matching.window_px / config_.camera.fx, matches_);
  } else {
    matcher_.match(kf.features.descriptors, curr.features.descriptors, matches_);
  }
  usable_.clear();
  for (size_t k = 0; k < matches_.size(); ++k)
    if (kf.points[static_cast<size_t>(matches_[k].prev)].z() > 0 && curr_points_[static_cast<size_t>(matches_[k].curr)].z() > 0)
      usable_.push_back(static_cast<int>(k));
  if (usable_.size() < static_cast<size_t>(config_.ransac.min_inliers)) return false;
  // The keyframe's patches found in the current image: the current points where the
  // keyframe's are seen, below a pixel.
  const KeypointGeometry* geometry = &curr.geometry;
  const std::vector<Eigen::Vector3d>* points = &curr_points_;
  if (tracking_ && !kf.gray.empty() && !curr.gray.empty() &&
      tracker_.track(kf.gray, kf.geometry, curr.gray, curr.geometry, curr.features.keypoints, matches_, usable_,
                     tracked_) > 0) {
    geometry = &tracked_;
    anchored_points(tracked_, curr.times, motion_, config_.camera.fx, config_.camera.fy, tracked_points_);
    points = &tracked_points_;
  }
  pair_kf_.clear();
  pair_curr_.clear();
  pair_covariances_.prev.clear();
  pair_covariances_.curr.clear();
  pair_cells_.clear();
  const double cell_px = config_.covariance.resample_cell_px > 0 ? config_.covariance.resample_cell_px : 1e9;
  const int cell_columns = static_cast<int>(std::ceil(config_.camera.width / cell_px));
  const int top_level = config_.features.orb_levels - 1;
  for (int k : usable_) {
    const Match& m = matches_[static_cast<size_t>(k)];
    const auto i = static_cast<size_t>(m.prev), j = static_cast<size_t>(m.curr);
    const Eigen::Vector3d& a = kf.points[i];
    const Eigen::Vector3d& b = (*points)[j];
    if (!(a.z() > 0) || !(b.z() > 0)) continue;
    pair_kf_.push_back(a);
    pair_curr_.push_back(b);
    const int level = std::clamp(curr.features.keypoints[j].octave, 0, top_level);
    pair_covariances_.prev.push_back(physical_point_noise(a, kf.levels[i], kf.geometry.depth_gradient[i], noise_).covariance());
    pair_covariances_.curr.push_back(physical_point_noise(b, level, geometry->depth_gradient[j], noise_).covariance());
    const Eigen::Vector2d& u = geometry->pixel[j];
    pair_cells_.push_back(std::clamp(static_cast<int>(u.y() / cell_px), 0, 255) * cell_columns +
                          std::clamp(static_cast<int>(u.x() / cell_px), 0, cell_columns - 1));
  }
  if (pair_kf_.size() < static_cast<size_t>(config_.ransac.min_inliers)) return false;
  ransac_.refine(pair_kf_, pair_curr_, T_pred, fit_, &pair_covariances_);
  if (fit_.status != Status::Ok || fit_.inliers.size() < static_cast<size_t>(config_.ransac.min_inliers)) return false;
  out.T = fit_.T_prev_curr;
  out.covariance = rigid_fit_covariance(pair_kf_, pair_curr_, fit_.inliers, pair_covariances_, pair_cells_, out.T);
  out.inliers = static_cast<int>(fit_.inliers.size());
  if (!(out.covariance.allFinite() && out.covariance.trace() > 0)) return false;
  if (depth_alignable(kf, curr)) {
    // Where the depth is aligned, a keyframe the frame is leaving is not measured: its alignment
    // would be paid for twice, the switch that follows measuring the frame again; unrefined, its
    // pull would move the pose further than the alignment lets it err (ICL-NUIM pairs 0.090 ->
    // 0.145 mm).
    if (!holds(kf, out.inliers)) return false;
    refine_with_depth(kf, curr, out);
  }
  // Measured between the two frames' depth instants, as the pair was: to their colour instants.
  out.T = at_colour_instants(out.T, kf.depth_shift, curr_depth_shift_);
  return true;
}

bool KeyframeTracker::depth_alignable(const Keyframe& kf, const ProcessedFrame& curr) const {
  // Colour and depth of one frame taken within this of each other count as taken together.
  constexpr std::int64_t kTogetherNs = 1'000'000;
  return depth_trusted_ && !kf.cloud.empty() && !curr.cloud.empty() &&
         std::abs(kf.times.t_colour_ns - kf.times.t_depth_ns) <= kTogetherNs &&
         std::abs(curr.times.t_colour_ns - curr.times.t_depth_ns) <= kTogetherNs;
}

void KeyframeTracker::refine_with_depth(const Keyframe& kf, const ProcessedFrame& curr, Measurement& out) {
  aligner_.align(kf.cloud, curr.cloud, out.T, alignment_);
  if (!alignment_.ok) return;
  Vector6d k;
  k << Eigen::Vector3d::Constant(depth_scale_t_), Eigen::Vector3d::Constant(depth_scale_r_);
  const Matrix6d depth_cov = k.asDiagonal() * alignment_.covariance * k.asDiagonal();
  Eigen::Isometry3d fused;
  Matrix6d fused_cov;
  if (!fuse_estimates(out.T, out.covariance, alignment_.T_prev_curr, depth_cov, alignment_.basis,
                      alignment_.constrained, fused, fused_cov)) {
    // They disagree. On depth the pair stage trusts, it is the features' fit against a keyframe
    // some frames back that errs beyond its covariance (ICL-NUIM: 0.5-2.5 mm against a sigma of
    // 0.3-0.5 mm, where the alignment is within a tenth of a millimetre of the chain), and kept
    // it would fail the chain's gate and abandon a keyframe that still holds (9 keyframes made
    // on the ICL-NUIM head's 100 frames, 4 with the alignment alone). Alone, the alignment must constrain
    // every direction; the chain's gate still judges it.
    if (alignment_.constrained == 6) {
      out.T = alignment_.T_prev_curr;
      out.covariance = depth_cov;
    }
    return;
  }
  out.T = fused;
  out.covariance = fused_cov;
}

Matrix6d KeyframeTracker::pose_covariance() const {
  if (active_ < 0) return Matrix6d::Zero();
  return carried(kept_[static_cast<size_t>(active_)].pose_covariance, se3_adjoint(T_kf_curr_.inverse())) + cov_kf_curr_;
}

int KeyframeTracker::most_overlapping(int except) const {
  int best = -1;
  double best_share = kMinReturnOverlap;
  const CameraConfig& c = config_.camera;
  const double border = config_.features.border_px;
  for (size_t k = 0; k < kept_.size(); ++k) {
    if (static_cast<int>(k) == except || !kept_[k].live) continue;
    const Eigen::Isometry3d curr_from_kf = pose_.inverse() * kept_[k].pose;
    int valid = 0, seen = 0;
    for (const Eigen::Vector3d& p : kept_[k].points) {
      if (!(p.z() > 0)) continue;
      ++valid;
      const Eigen::Vector3d q = curr_from_kf * p;
      if (!(q.z() > 0)) continue;
      const double u = c.fx * q.x() / q.z() + c.cx, v = c.fy * q.y() / q.z() + c.cy;
      if (u >= border && v >= border && u < c.width - border && v < c.height - border) ++seen;
    }
    const double share = valid > 0 ? static_cast<double>(seen) / valid : 0;
    if (share > best_share) {
      best_share = share;
      best = static_cast<int>(k);
    }
  }
  return best;
}

void KeyframeTracker::make_keyframe(const ProcessedFrame& curr) {
  const Matrix6d pose_cov = pose_covariance();
  // A free slot, or the least recently used keyframe's.
  const auto slot = static_cast<size_t>(
      std::min_element(kept_.begin(), kept_.end(),
                       [](const Keyframe& a, const Keyframe& b) {
                         return std::make_pair(a.live, a.last_used) < std::make_pair(b.live, b.last_used);
                       }) -
      kept_.begin());
  Keyframe& kf = kept_[slot];
  kf.features.keypoints = curr.features.keypoints;
  const cv::Mat& d = curr.features.descriptors;
  cv::Mat& storage = kf.features.descriptor_storage;
  if (storage.rows < d.rows || storage.cols != d.cols || storage.type() != d.type())
    storage.create(std::max(d.rows, config_.features.max_features), d.cols, d.type());
  kf.features.descriptors = storage.rowRange(0, d.rows);
  d.copyTo(kf.features.descriptors);
  kf.points = curr_points_;
  kf.geometry = curr.geometry;
  kf.times = curr.times;
  kf.depth_shift = curr_depth_shift_;
  kf.cloud = curr.cloud;
  if (tracking_) curr.gray.copyTo(kf.gray);
  kf.levels.resize(curr.features.keypoints.size());
  for (size_t i = 0; i < kf.levels.size(); ++i)
    kf.levels[i] = std::clamp(curr.features.keypoints[i].octave, 0, config_.features.orb_levels - 1);
  kf.pose = pose_;
  kf.pose_covariance = pose_cov;
  kf.live = true;
  kf.reference_inliers = 0;
  kf.id = next_id_++;
  kf.last_used = frames_;
  active_ = static_cast<int>(slot);
  T_kf_curr_ = Eigen::Isometry3d::Identity();
  cov_kf_curr_ = Matrix6d::Zero();
}

void KeyframeTracker::update(const ProcessedFrame& curr, PairResult& pair) {
  if (!config_.keyframes.enabled) return;
  if (pair.status != Status::Ok) {
    // An unknown motion (the pair contributes none): the chain ends here.
    for (Keyframe& kf : kept_) kf.live = false;
    active_ = -1;
    return;
  }
  mark_cost_stage(CostStage::Keyframe);
  const CostStagesEnd stages_end;
  const auto start = std::chrono::steady_clock::now();
  struct Timed {  // the stage's wall time into the pair, on every return
    PairResult& pair;
    std::chrono::steady_clock::time_point start;
    ~Timed() { pair.times.keyframe_ms = ms_since(start); }
  } timed{pair, start};
  ++frames_;
  const double dt_s = static_cast<double>(pair.t_curr_ns - pair.t_prev_ns) * 1e-9;
  own_motion_ = dt_s > 0 ? motion_from(pair.T_prev_curr, dt_s) : MotionPrior{};
  curr_depth_shift_ = pair.depth_shift;
  motion_ = config_.depth.compensate_timing && dt_s > 0 ? &own_motion_ : nullptr;
  anchored_points(curr.geometry, curr.times, motion_, config_.camera.fx, config_.camera.fy, curr_points_);
  // The sensor's constants as the pair stage has learnt them, where it has.
  if (pair.sensor.depth_noise_coeff > 0) noise_.depth_noise_coeff = pair.sensor.depth_noise_coeff;
  if (pair.sensor.keypoint_sigma_fine_px > 0) noise_.pixel_sigma_px = pair.sensor.keypoint_sigma_fine_px;
  depth_trusted_ = pair.depth_trusted;
  depth_scale_t_ = std::max(1.0, pair.sensor.depth_sigma_scale_t);
  depth_scale_r_ = std::max(1.0, pair.sensor.depth_sigma_scale_r);

  if (active_ < 0) {
    pose_ = orthonormalised(pose_ * pair.T_prev_curr);
    make_keyframe(curr);
    pair.keyframe = {kept_[static_cast<size_t>(active_)].id, 0, true, false, true, Matrix6d::Zero()};
    return;
  }
  Keyframe& kf = kept_[static_cast<size_t>(active_)];
  const Eigen::Isometry3d T_kf_prev = T_kf_curr_;
  const Eigen::Isometry3d pose_prev = pose_;
  // The frame pair predicts; the keyframe measures.
  const Matrix6d carry = se3_adjoint(pair.T_prev_curr.inverse());
  const Eigen::Isometry3d T_pred = T_kf_prev * pair.T_prev_curr;
  const Matrix6d cov_pred =
      extended(carried(cov_kf_curr_, carry), right_perturbation_covariance(pair.T_prev_curr, pair.motion_covariance));
  Measurement z;
  const bool measured = measure(kf, curr, T_pred, z) && agree(T_pred, cov_pred, z);
  if (measured) {
    correct(T_pred, cov_pred, z);
  } else {
    T_kf_curr_ = T_pred;
    cov_kf_curr_ = cov_pred;
  }
  pose_ = orthonormalised(kf.pose * T_kf_curr_);
  kf.last_used = frames_;
  if (measured && kf.reference_inliers == 0) kf.reference_inliers = z.inliers;
  pair.keyframe = {kf.id, measured ? z.inliers : 0, false, false, false, Matrix6d::Zero()};

  if (!measured || !holds(kf, z.inliers)) {
    // The view has moved on: back to an earlier keyframe that sees it, or a new one.
    const int back = most_overlapping(active_);
    bool returned = false;
    if (back >= 0) {
      Keyframe& old = kept_[static_cast<size_t>(back)];
      const Eigen::Isometry3d T_back = old.pose.inverse() * pose_;
      const Matrix6d carry_back = se3_adjoint(T_back.inverse());
      const Matrix6d cov_back = carried(old.pose_covariance, carry_back) + pose_covariance();
      Measurement zb;
      if (measure(old, curr, T_back, zb) && holds(old, zb.inliers) && agree(T_back, cov_back, zb)) {
        active_ = back;
        correct(T_back, cov_back, zb);
        pose_ = orthonormalised(old.pose * T_kf_curr_);
        old.last_used = frames_;
        pair.keyframe = {old.id, zb.inliers, false, true};
        returned = true;
      }
    }
    if (!returned) {
      make_keyframe(curr);
      pair.keyframe.created = true;
      pair.keyframe.id = kept_[static_cast<size_t>(active_)].id;
    }
  }
  pair.T_prev_curr = orthonormalised(pose_prev.inverse() * pose_);
  pair.keyframe.pose_covariance = pose_covariance();
}

}  // namespace rgbdo
