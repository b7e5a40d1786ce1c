// The perturbation covariance: 100 perturbations of 300 inlier pairs, noise generation
// included. The project's batched version (vectorised noise, SoA sums for all perturbations,
// one 3x3 solve each) beside the obvious loop: std::normal_distribution noise into
// Eigen::Matrix3Xd clouds and Eigen::umeyama per perturbation; in one run.
#include <benchmark/benchmark.h>

#include <Eigen/Geometry>
#include <random>

#include "benchmark_loops.hpp"
#include "paper_reproduction.hpp"
#include "rgbd_odometry/pipeline/covariance.hpp"
#include "rgbd_odometry/pipeline/noise_model.hpp"

namespace rgbdo {
namespace {

constexpr int kPairs = 300;
constexpr int kPerturbations = 100;

Eigen::Isometry3d inliers_motion() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.01, -0.005, 0.02);
  return T;
}

// Noise-free inliers of a pure translation.
const SyntheticPairs& inliers() {
  static const SyntheticPairs s = synthetic_pairs(kPairs, inliers_motion(), 0, 0, 5);
  return s;
}

CovarianceConfig benchmark_config() {
  CovarianceConfig config;
  config.perturbations = kPerturbations;
  return config;
}

void count_perturbations(benchmark::State& state, const PerturbationCovariance& cov) {
  state.SetLabel(std::string("kernel ") + cov.kernel_name());
  state.counters["perturbations/s"] = per_second(static_cast<double>(state.iterations()) * kPerturbations);
}

void BM_Covariance_Batched(benchmark::State& state) {
  const auto& s = inliers();
  PerturbationCovariance cov(benchmark_config(), kPairs);
  const Eigen::Isometry3d T = inliers_motion();
  Matrix6d c;
  std::uint64_t seed = 0;
  for (auto _ : state) {
    Rng rng(seed++);
    benchmark::DoNotOptimize(cov.estimate(s.prev, s.curr, T, rng, c));
  }
  count_perturbations(state, cov);
}
BENCHMARK(BM_Covariance_Batched)->Unit(benchmark::kMicrosecond);

// The pipeline's default path: the physical model's per-point noise, the inliers resampled by
// 12 image cells in every perturbation, the variance factor and the capture-time term (two
// more weighted fits).
void BM_Covariance_BatchedPhysical(benchmark::State& state) {
  const auto& s = inliers();
  PerturbationCovariance cov(benchmark_config(), kPairs);
  const Eigen::Isometry3d T = inliers_motion();
  std::vector<PointNoise> np, nc;
  std::vector<std::uint16_t> cells;
  for (int k = 0; k < kPairs; ++k) {
    const auto i = static_cast<size_t>(k);
    np.push_back(physical_point_noise(s.prev[i], k % 8, Eigen::Vector2d(0.002, 0), SensorNoise{}));
    nc.push_back(physical_point_noise(s.curr[i], k % 8, Eigen::Vector2d(0.002, 0), SensorNoise{}));
    np.back().depth_rate_mps = nc.back().depth_rate_mps = -0.3;
    cells.push_back(static_cast<std::uint16_t>(k % 12));
  }
  Matrix6d c;
  std::uint64_t seed = 0;
  for (auto _ : state) {
    Rng rng(seed++);
    benchmark::DoNotOptimize(cov.estimate(s.prev, s.curr, np, nc, cells, T, 0.002, rng, c));
  }
  count_perturbations(state, cov);
}
BENCHMARK(BM_Covariance_BatchedPhysical)->Unit(benchmark::kMicrosecond);

void BM_Covariance_EigenUmeyamaLoop(benchmark::State& state) {
  const auto& s = inliers();
  std::mt19937_64 rng(1);
  for (auto _ : state) {
    const Matrix6d c = straightforward_covariance(s.prev, s.curr, 1.425e-3, kPerturbations, rng);
    benchmark::DoNotOptimize(c.data());
  }
  state.counters["perturbations/s"] = per_second(static_cast<double>(state.iterations()) * kPerturbations);
}
BENCHMARK(BM_Covariance_EigenUmeyamaLoop)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace rgbdo

BENCHMARK_MAIN();
