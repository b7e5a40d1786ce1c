// RANSAC over 3-point samples: 500 correspondences, 40 % outliers, exactly 200 hypotheses
// (adaptive stopping off). The project's allocation-free RANSAC, its hypothesis stage alone
// (the same work as the alternative) and whole (with the threshold refinement and the final
// anisotropic fit), beside the straightforward Eigen version: Eigen::umeyama on each
// triplet, every point transformed as an Eigen::Matrix3Xd, inliers counted; in one run.
#include <benchmark/benchmark.h>

#include <Eigen/Geometry>
#include <random>

#include "benchmark_loops.hpp"
#include "rgbd_odometry/core/geometry.hpp"
#include "rgbd_odometry/pipeline/ransac.hpp"

namespace rgbdo {
namespace {

constexpr int kPairs = 500;
constexpr int kHypotheses = 200;

// 40 % outliers, inliers with 3 mm noise; also as 3 x N matrices for the Eigen version.
struct Scene {
  std::vector<Eigen::Vector3d> prev, curr;
  Eigen::Matrix3Xd P, Q;
  Scene() {
    Vector6d xi;
    xi << 0.02, -0.01, 0.03, 0.01, -0.02, 0.015;
    SyntheticPairs pairs = synthetic_pairs(kPairs, transform_from_xi(xi), 0.003, 0.4, 4);
    prev = std::move(pairs.prev);
    curr = std::move(pairs.curr);
    P = Eigen::Map<const Eigen::Matrix3Xd>(prev.data()->data(), 3, kPairs);
    Q = Eigen::Map<const Eigen::Matrix3Xd>(curr.data()->data(), 3, kPairs);
  }
};

const Scene& scene() {
  static const Scene s;
  return s;
}

// kHypotheses every call (no adaptive stop): the same work whatever the draws.
RansacConfig fixed_hypotheses() {
  RansacConfig config;
  config.max_iterations = kHypotheses;
  config.adaptive_stop = false;
  return config;
}

void BM_Ransac_AllocationFree(benchmark::State& state) {
  RigidRansac ransac(fixed_hypotheses(), SensorNoise{}, kPairs);
  measure_ransac(state, ransac, scene().prev, scene().curr);
}
BENCHMARK(BM_Ransac_AllocationFree)->Unit(benchmark::kMicrosecond);

// The same work as the Eigen version below: 200 hypotheses, the best one kept.
void BM_Ransac_HypothesesOnly(benchmark::State& state) {
  const auto& s = scene();
  RigidRansac ransac(fixed_hypotheses(), SensorNoise{}, kPairs);
  Eigen::Isometry3d best;
  std::uint64_t seed = 0;
  int hypotheses = 0;
  for (auto _ : state) {
    Rng rng(seed++);
    hypotheses += ransac.sample_hypotheses(s.prev, s.curr, rng, best);
    benchmark::DoNotOptimize(best.data());
  }
  state.counters["hypotheses/s"] = per_second(hypotheses);
}
BENCHMARK(BM_Ransac_HypothesesOnly)->Unit(benchmark::kMicrosecond);

void BM_Ransac_StraightforwardEigen(benchmark::State& state) {
  const auto& s = scene();
  std::mt19937 rng(1);
  std::uniform_int_distribution<int> pick(0, kPairs - 1);
  int best = 0;
  for (auto _ : state) {
    best = 0;
    for (int h = 0; h < kHypotheses; ++h) {
      int i = pick(rng), j = pick(rng), k = pick(rng);
      while (j == i) j = pick(rng);
      while (k == i || k == j) k = pick(rng);
      Eigen::Matrix3Xd src(3, 3), dst(3, 3);
      src << s.Q.col(i), s.Q.col(j), s.Q.col(k);
      dst << s.P.col(i), s.P.col(j), s.P.col(k);
      const Eigen::Matrix4d T = Eigen::umeyama(src, dst, false);
      const Eigen::Matrix3Xd moved = (T.topLeftCorner<3, 3>() * s.Q).colwise() + T.topRightCorner<3, 1>();
      const int count = static_cast<int>(((s.P - moved).colwise().squaredNorm().array() < 0.05 * 0.05).count());
      best = std::max(best, count);
    }
    benchmark::DoNotOptimize(best);
  }
  state.counters["inliers"] = best;
  state.counters["hypotheses/s"] = per_second(static_cast<double>(state.iterations()) * kHypotheses);
}
BENCHMARK(BM_Ransac_StraightforwardEigen)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace rgbdo

BENCHMARK_MAIN();
