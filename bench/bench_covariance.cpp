// The perturbation covariance: 100 perturbations of 300 inlier pairs, noise generation
// included. The project's batched version (vectorised noise, SoA sums for all perturbations,
// one 3x3 solve each) beside the obvious loop: std::normal_distribution noise into
// Eigen::Matrix3Xd clouds and Eigen::umeyama per perturbation; in one run.
#include <benchmark/benchmark.h>

#include <Eigen/Geometry>
#include <random>

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
  Eigen::Matrix3Xd src(3, kPairs), dst(3, kPairs), sigma_src(3, kPairs), sigma_dst(3, kPairs);
  for (int k = 0; k < kPairs; ++k) {
    src.col(k) = s.curr[static_cast<size_t>(k)];
    dst.col(k) = s.prev[static_cast<size_t>(k)];
    sigma_src.col(k) = point_sigma(s.curr[static_cast<size_t>(k)], 1.425e-3);
    sigma_dst.col(k) = point_sigma(s.prev[static_cast<size_t>(k)], 1.425e-3);
  }
  std::mt19937_64 rng(1);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (auto _ : state) {
    std::vector<Vector6d> xs;
    for (int p = 0; p < kPerturbations; ++p) {
      Eigen::Matrix3Xd noisy_src = src, noisy_dst = dst;
      for (int k = 0; k < kPairs; ++k)
        for (int c = 0; c < 3; ++c) {
          noisy_src(c, k) += sigma_src(c, k) * gauss(rng);
          noisy_dst(c, k) += sigma_dst(c, k) * gauss(rng);
        }
      const Eigen::Matrix4d T = Eigen::umeyama(noisy_src, noisy_dst, false);
      Vector6d xi;
      xi.head<3>() = T.topRightCorner<3, 1>();
      const Eigen::AngleAxisd aa(Eigen::Matrix3d(T.topLeftCorner<3, 3>()));
      xi.tail<3>() = aa.axis() * aa.angle();
      xs.push_back(xi);
    }
    Vector6d mean = Vector6d::Zero();
    for (const auto& x : xs) mean += x;
    mean /= kPerturbations;
    Matrix6d c = Matrix6d::Zero();
    for (const auto& x : xs) c += (x - mean) * (x - mean).transpose();
    benchmark::DoNotOptimize(c.data());
  }
  state.counters["perturbations/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * kPerturbations, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Covariance_EigenUmeyamaLoop)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace rgbdo

BENCHMARK_MAIN();
