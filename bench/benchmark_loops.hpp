#pragma once
// What the Google Benchmark programs measure alike: a rate counter, a synthetic scene of point
// pairs, RANSAC over one set of point pairs, frames through a pipeline.
#include <benchmark/benchmark.h>

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <random>
#include <vector>

#include "rgbd_odometry/core/rng.hpp"
#include "rgbd_odometry/pipeline/ransac.hpp"

namespace rgbdo {

// `count` over the benchmark's time: a per-second counter.
inline benchmark::Counter per_second(double count) { return benchmark::Counter(count, benchmark::Counter::kIsRate); }

// n point pairs over a 2 x 1.5 m field 1-3 m ahead: prev = T curr plus Gaussian noise of
// sigma_m on each axis, but for a share of outliers whose prev is anywhere in the field.
struct SyntheticPairs {
  std::vector<Eigen::Vector3d> prev, curr;
};
inline SyntheticPairs synthetic_pairs(int n, const Eigen::Isometry3d& T, double sigma_m, double outlier_share,
                                      unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1), z(1, 3), unit(0, 1);
  std::normal_distribution<double> g(0, 1);
  const auto field_point = [&] { return Eigen::Vector3d(u(rng), 0.75 * u(rng), z(rng)); };
  SyntheticPairs pairs;
  for (int i = 0; i < n; ++i) {
    pairs.curr.push_back(field_point());
    const bool outlier = unit(rng) < outlier_share;
    pairs.prev.push_back(outlier ? field_point()
                                 : Eigen::Vector3d(T * pairs.curr.back() + sigma_m * Eigen::Vector3d(g(rng), g(rng), g(rng))));
  }
  return pairs;
}

// `ransac` on the same point pairs, a new seed each iteration: hypotheses/s, the pairs and the
// last run's inliers.
inline void measure_ransac(benchmark::State& state, RigidRansac& ransac, const std::vector<Eigen::Vector3d>& prev,
                           const std::vector<Eigen::Vector3d>& curr) {
  RansacResult r;
  std::uint64_t seed = 0;
  int hypotheses = 0;
  for (auto _ : state) {
    Rng rng(seed++);
    ransac.estimate(prev, curr, rng, r);
    hypotheses += r.hypotheses;
  }
  state.counters["pairs"] = static_cast<double>(prev.size());
  state.counters["inliers"] = static_cast<double>(r.inliers.size());
  state.counters["hypotheses/s"] = per_second(hypotheses);
}

// One frame an iteration through `process(i)` (frame i of the loop), which returns whether that
// frame's pair failed: frames/s and the failures.
template <class Process>
void measure_frames(benchmark::State& state, Process process) {
  std::size_t i = 0;
  int failed = 0;
  for (auto _ : state) failed += process(i++) ? 1 : 0;
  state.counters["frames/s"] = per_second(static_cast<double>(state.iterations()));
  state.counters["failed"] = failed;
}

}  // namespace rgbdo
