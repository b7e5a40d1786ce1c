// RANSAC over 3-point samples: 500 correspondences, 40 % outliers, exactly 200 hypotheses
// (adaptive stopping off). The project's allocation-free RANSAC, its hypothesis stage alone
// (the same work as the alternative) and whole (with the threshold refinement and the final
// anisotropic fit), beside the straightforward Eigen version: Eigen::umeyama on each
// triplet, every point transformed as an Eigen::Matrix3Xd, inliers counted; in one run.
#include <benchmark/benchmark.h>

#include <Eigen/Geometry>
#include <random>

#include "rgbd_odometry/core/geometry.hpp"
#include "rgbd_odometry/pipeline/ransac.hpp"

namespace rgbdo {
namespace {

constexpr int kPairs = 500;
constexpr int kHypotheses = 200;

struct Scene {
  std::vector<Eigen::Vector3d> prev, curr;
  Eigen::Matrix3Xd P, Q;
  Scene() : P(3, kPairs), Q(3, kPairs) {
    std::mt19937 rng(4);
    std::uniform_real_distribution<double> u(-1, 1), z(1, 3), unit(0, 1);
    std::normal_distribution<double> g(0, 0.003);
    Vector6d xi;
    xi << 0.02, -0.01, 0.03, 0.01, -0.02, 0.015;
    const Eigen::Isometry3d T = transform_from_xi(xi);
    for (int i = 0; i < kPairs; ++i) {
      const Eigen::Vector3d c(u(rng), 0.75 * u(rng), z(rng));
      const bool outlier = unit(rng) < 0.4;
      curr.push_back(c);
      prev.push_back(outlier ? Eigen::Vector3d(u(rng), 0.75 * u(rng), z(rng))
                             : Eigen::Vector3d(T * c + Eigen::Vector3d(g(rng), g(rng), g(rng))));
      P.col(i) = prev.back();
      Q.col(i) = c;
    }
  }
};

const Scene& scene() {
  static const Scene s;
  return s;
}

void BM_Ransac_AllocationFree(benchmark::State& state) {
  const auto& s = scene();
  RansacConfig config;
  config.max_iterations = kHypotheses;
  config.adaptive_stop = false;
  RigidRansac ransac(config, SensorNoise{}, kPairs);
  RansacResult r;
  std::uint64_t seed = 0;
  int hypotheses = 0;
  for (auto _ : state) {
    Rng rng(seed++);
    ransac.estimate(s.prev, s.curr, rng, r);
    hypotheses += r.hypotheses;
  }
  state.counters["inliers"] = static_cast<double>(r.inliers.size());
  state.counters["hypotheses/s"] = benchmark::Counter(hypotheses, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Ransac_AllocationFree)->Unit(benchmark::kMicrosecond);

// The same work as the Eigen version below: 200 hypotheses, the best one kept.
void BM_Ransac_HypothesesOnly(benchmark::State& state) {
  const auto& s = scene();
  RansacConfig config;
  config.max_iterations = kHypotheses;
  config.adaptive_stop = false;
  RigidRansac ransac(config, SensorNoise{}, kPairs);
  Eigen::Isometry3d best;
  std::uint64_t seed = 0;
  int hypotheses = 0;
  for (auto _ : state) {
    Rng rng(seed++);
    hypotheses += ransac.sample_hypotheses(s.prev, s.curr, rng, best);
    benchmark::DoNotOptimize(best.data());
  }
  state.counters["hypotheses/s"] = benchmark::Counter(hypotheses, benchmark::Counter::kIsRate);
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
  state.counters["hypotheses/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * kHypotheses, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Ransac_StraightforwardEigen)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace rgbdo

BENCHMARK_MAIN();
