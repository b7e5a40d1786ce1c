#pragma once
// The project's first, straightforward RANSAC, kept as the paper reproduction's
// (paper_reproduction.hpp): the obvious alternative the benchmarks measure the allocation-free
// hypothesis stage against. std::vector results, fit_rigid (SVD) on every triplet,
// double-precision scoring of Eigen vectors; the refinement that follows is the project's own
// (RigidRansac::refine), which both run alike. The tests check RigidRansac against an oracle of
// their own (test/ransac_oracle.hpp), not against this.
#include <Eigen/Geometry>
#include <algorithm>
#include <vector>

#include "rgbd_odometry/app/config.hpp"
#include "rgbd_odometry/pipeline/noise_model.hpp"
#include "rgbd_odometry/pipeline/ransac.hpp"
#include "rgbd_odometry/core/rng.hpp"
#include "rgbd_odometry/core/status.hpp"
#include "rgbd_odometry/core/umeyama.hpp"

namespace rgbdo {

using StraightforwardResult = RansacResult;

class StraightforwardRansac {
 public:
  StraightforwardRansac(const RansacConfig& ransac, const SensorNoise& noise);

  // prev[k] ~ T * curr[k] for inliers k.
  [[nodiscard]] StraightforwardResult estimate(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                                      Rng& rng);

  // The refinement alone, from a given motion (used again after the points were corrected).
  [[nodiscard]] StraightforwardResult refine(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                                    const Eigen::Isometry3d& initial);

 private:
  RansacConfig config_;
  RigidRansac refiner_;  // its refinement only: buffers grow as needed (no capacity set aside)
};

inline StraightforwardRansac::StraightforwardRansac(const RansacConfig& ransac, const SensorNoise& noise)
    : config_(ransac), refiner_(ransac, noise, 0) {}

inline StraightforwardResult StraightforwardRansac::estimate(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                                   Rng& rng) {
  StraightforwardResult result;
  const int n = static_cast<int>(prev.size());
  if (n < std::max(3, config_.min_inliers)) return result;

  const double threshold_sq = config_.inlier_threshold_m * config_.inlier_threshold_m;
  int best_count = -1;
  double best_cost = 0;
  Eigen::Isometry3d best = Eigen::Isometry3d::Identity();
  int needed = config_.max_iterations;
  // Degenerate draws are cheap and do not count as hypotheses, but are bounded too.
  const int max_draws = 10 * config_.max_iterations;
  for (int draw = 0; draw < max_draws && result.hypotheses < needed; ++draw) {
    Eigen::Vector3d s[3], d[3];
    if (!draw_sample(rng, prev, curr, config_.inlier_threshold_m, s, d)) continue;
    Eigen::Isometry3d T;
    if (!fit_rigid(s, d, {}, T)) continue;
    ++result.hypotheses;

    // Score: inlier count, ties broken by the truncated squared error (MSAC's cost).
    int count = 0;
    double cost = 0;
    for (int k = 0; k < n; ++k) {
      const double e = (prev[static_cast<size_t>(k)] - T * curr[static_cast<size_t>(k)]).squaredNorm();
      if (e < threshold_sq) {
        ++count;
        cost += e;
      } else {
        cost += threshold_sq;
      }
    }
    if (count > best_count || (count == best_count && cost < best_cost)) {
      best_count = count;
      best_cost = cost;
      best = T;
      needed = adaptive_hypotheses(count, n, config_.max_iterations);
    }
  }
  if (best_count < 0) {
    result.status = Status::DegenerateSample;
    return result;
  }
  const int hypotheses = result.hypotheses;
  result = refine(prev, curr, best);
  result.hypotheses = hypotheses;
  return result;
}

inline StraightforwardResult StraightforwardRansac::refine(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                                 const Eigen::Isometry3d& initial) {
  StraightforwardResult result;
  refiner_.refine(prev, curr, initial, result);
  return result;
}

}  // namespace rgbdo
