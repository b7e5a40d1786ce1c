// The perturbation covariance: 100 perturbations of 300 inlier pairs, noise generation
// included. The project's batched version (vectorised noise, SoA sums for all perturbations,
// one 3x3 solve each) beside the obvious loop: std::normal_distribution noise into
// Eigen::Matrix3Xd clouds and Eigen::umeyama per perturbation; in one run.
#include <benchmark/benchmark.h>

#include <Eigen/Geometry>
#include <random>

#include "paper_reproduction.hpp"
#include "rgbd_odometry/pipeline/covariance.hpp"
#include "rgbd_odometry/core/noise_model.hpp"

namespace rgbdo {
namespace {

constexpr int kPairs = 300;
constexpr int kPerturbations = 100;

struct Inliers {
  std::vector<Eigen::Vector3d> prev, curr;
  Inliers() {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1, 1), z(1, 3);
    for (int i = 0; i < kPairs; ++i) {
      curr.emplace_back(u(rng), 0.75 * u(rng), z(rng));
      prev.push_back(curr.back() + Eigen::Vector3d(0.01, -0.005, 0.02));
    }
  }
};

const Inliers& inliers() {
  static const Inliers s;
  return s;
}

void BM_Covariance_Batched(benchmark::State& state) {
  const auto& s = inliers();
  CovarianceConfig config;
  config.perturbations = kPerturbations;
  PerturbationCovariance cov(config, kPairs);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.01, -0.005, 0.02);
  Matrix6d c;
  std::uint64_t seed = 0;
  for (auto _ : state) {
    Rng rng(seed++);
    benchmark::DoNotOptimize(cov.estimate(s.prev, s.curr, T, rng, c));
  }
  state.SetLabel(std::string("kernel ") + cov.kernel_name());
  state.counters["perturbations/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * kPerturbations, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Covariance_Batched)->Unit(benchmark::kMicrosecond);

void BM_Covariance_EigenUmeyamaLoop(benchmark::State& state) {
  const auto& s = inliers();
  std::mt19937_64 rng(1);
  for (auto _ : state) {
    const Matrix6d c = straightforward_covariance(s.prev, s.curr, 1.425e-3, kPerturbations, rng);
    benchmark::DoNotOptimize(c.data());
  }
  state.counters["perturbations/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * kPerturbations, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Covariance_EigenUmeyamaLoop)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace rgbdo

BENCHMARK_MAIN();
