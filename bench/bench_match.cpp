// Symmetric matching of 1000 x 1000 real ORB descriptors (bundled fr1_xyz frames 0 and 1):
// each compiled kernel set, and the obvious alternative, two cv::BFMatcher(NORM_HAMMING)
// knnMatch(k = 2) calls followed by the same symmetric ratio test, in one run.
#include <benchmark/benchmark.h>

#include <opencv2/core/utility.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>

#include "benchmark_loops.hpp"
#include "rgbd_odometry/simd/kernels.hpp"
#include "rgbd_odometry/pipeline/match.hpp"
#include "rgbd_odometry/io/tum_sequence.hpp"

namespace rgbdo {
namespace {

constexpr int kDescriptors = 1000;

struct Descriptors {
  cv::Mat a, b;
  Descriptors() {
    cv::setNumThreads(1);
    const TumSequence seq = open_tum_sequence(RGBDO_TEST_DATA_DIR);
    auto orb = cv::ORB::create(2 * kDescriptors);  // detect more, keep exactly 1000
    const auto describe = [&](const std::string& path) {
      std::vector<cv::KeyPoint> kps;
      cv::Mat d;
      orb->detectAndCompute(cv::imread(path, cv::IMREAD_GRAYSCALE), cv::noArray(), kps, d);
      if (d.rows < kDescriptors) throw std::runtime_error("too few ORB descriptors in " + path);
      return d.rowRange(0, kDescriptors).clone();
    };
    a = describe(seq.frames[0].colour_path);
    b = describe(seq.frames[1].colour_path);
  }
};

const Descriptors& descriptors() {
  static const Descriptors d;
  return d;
}

void set_rate(benchmark::State& state) {
  state.counters["descriptor_pairs/s"] = per_second(static_cast<double>(state.iterations()) * kDescriptors * kDescriptors);
}

void BM_NearestTwo(benchmark::State& state, const simd::KernelSet* set) {
  const auto& d = descriptors();
  std::vector<simd::NearestTwo> qa(kDescriptors), tb(kDescriptors);
  for (auto _ : state) {
    set->nearest_two_hamming(d.a.data, d.a.rows, d.a.step, d.b.data, d.b.rows, d.b.step, 32, qa.data(), tb.data());
    benchmark::DoNotOptimize(qa.data());
  }
  set_rate(state);
}

void BM_SymmetricMatch(benchmark::State& state) {
  const auto& d = descriptors();
  SymmetricMatcher matcher(0.8);
  std::vector<Match> out;
  for (auto _ : state) {
    matcher.match(d.a, d.b, out);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetLabel(std::string("kernel ") + matcher.kernel_name());
  state.counters["matches"] = static_cast<double>(out.size());
  set_rate(state);
}
BENCHMARK(BM_SymmetricMatch)->Unit(benchmark::kMillisecond);

void BM_SymmetricMatch_BFMatcherKnn2x(benchmark::State& state) {
  const auto& d = descriptors();
  cv::BFMatcher bf(cv::NORM_HAMMING);
  std::vector<std::vector<cv::DMatch>> ab, ba;
  int kept = 0;
  for (auto _ : state) {
    ab.clear();  // knnMatch appends to its output
    ba.clear();
    bf.knnMatch(d.a, d.b, ab, 2);
    bf.knnMatch(d.b, d.a, ba, 2);
    kept = 0;
    for (const auto& m : ab) {
      if (m.size() < 2 || !(m[0].distance < 0.8f * m[1].distance)) continue;
      const auto& r = ba[static_cast<size_t>(m[0].trainIdx)];
      kept += r.size() == 2 && r[0].trainIdx == m[0].queryIdx && r[0].distance < 0.8f * r[1].distance;
    }
    benchmark::DoNotOptimize(kept);
  }
  state.counters["matches"] = kept;
  set_rate(state);
}
BENCHMARK(BM_SymmetricMatch_BFMatcherKnn2x)->Unit(benchmark::kMillisecond);

[[maybe_unused]] const bool registered = [] {
  for (const auto& s : simd::compiled_kernel_sets())
    if (simd::cpu_supports(s))
      benchmark::RegisterBenchmark((std::string("BM_NearestTwo/") + s.name).c_str(), BM_NearestTwo, &s)
          ->Unit(benchmark::kMillisecond);
  return true;
}();

}  // namespace
}  // namespace rgbdo

BENCHMARK_MAIN();
