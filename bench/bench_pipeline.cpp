// Per-stage and whole-pipeline throughput on real frames (the bundled TUM fr1_xyz frames),
// one thread, PNG decoding excluded: where the time of a frame goes, and the whole pipeline
// beside a straightforward reproduction of the paper (BM_PaperReproduction). The per-stage
// ratios against the obvious alternatives are read from bench_match, bench_ransac and
// bench_covariance.
#include <benchmark/benchmark.h>

#include <opencv2/core/utility.hpp>
#include <opencv2/features2d.hpp>

#include "benchmark_loops.hpp"
#include "paper_reproduction.hpp"
#include "rgbd_odometry/pipeline/mask.hpp"
#include "rgbd_odometry/pipeline/odometry.hpp"
#include "rgbd_odometry/io/tum_sequence.hpp"
#include "rgbd_odometry/core/umeyama.hpp"
#include "rgbd_odometry/pipeline/frame_extractor.hpp"
#include "rgbd_odometry/app/config_file.hpp"

namespace rgbdo {
namespace {

constexpr int kFrames = 16;

struct Fixture {
  Config config;
  std::vector<RgbdFrame> frames;           // decoded once, outside any timing
  std::vector<ProcessedFrame> processed;   // features + geometry per frame
  std::vector<Match> matches;              // of frames 0 -> 1
  PointPairs pairs;                        // of frames 0 -> 1
  std::vector<Eigen::Vector3d> inlier_prev, inlier_curr;
  Eigen::Isometry3d motion;

  Fixture() : config(load_config(RGBDO_CONFIG_DIR "/tum-fr1.yaml")) {
    cv::setNumThreads(1);
    const TumSequence seq = open_tum_sequence(RGBDO_TEST_DATA_DIR);
    FrameExtractor extractor(config);
    for (int i = 0; i < kFrames; ++i) {
      frames.push_back(load_tum_frame(seq.frames[static_cast<size_t>(i)], config.depth.units_per_m, 640, 480));
      processed.emplace_back();
      extractor.extract(frames.back(), processed.back());
    }
    SymmetricMatcher(config.matching.ratio).match(processed[0].features.descriptors, processed[1].features.descriptors, matches);
    build_point_pairs(matches, processed[0].geometry, processed[0].times, processed[1].geometry, processed[1].times,
                      nullptr, pairs);
    RigidRansac ransac(config.ransac, SensorNoise{}, config.features.max_features);
    Rng rng(1);
    RansacResult r;
    ransac.estimate(pairs.prev, pairs.curr, rng, r);
    motion = r.T_prev_curr;
    for (int k : r.inliers) {
      inlier_prev.push_back(pairs.prev[static_cast<size_t>(k)]);
      inlier_curr.push_back(pairs.curr[static_cast<size_t>(k)]);
    }
  }
};

const Fixture& fixture() {
  static const Fixture f;
  return f;
}

// The fixture's frames forwards, then backwards, over and over, stamped 1/30 s apart (each
// keeping its own colour-to-depth offset): every iteration is a real pair, a camera going
// back over its path. Cycling 0..n-1, 0.. instead sends stamps backwards at each wrap, and
// the pipeline drops such a frame (and every frame after it stamped before the newest kept),
// so the loop would time extraction and a drop, not a pair.
RgbdFrame looped_frame(const std::vector<RgbdFrame>& frames, size_t iteration) {
  const size_t n = frames.size(), period = 2 * n - 2;
  const size_t k = iteration % period;
  RgbdFrame f = frames[k < n ? k : period - k];  // the images are shared, not copied
  const std::int64_t depth_offset = f.t_depth_ns - f.t_colour_ns;
  f.t_colour_ns = static_cast<std::int64_t>(iteration) * 33'333'333;
  f.t_depth_ns = f.t_colour_ns + depth_offset;
  return f;
}

void BM_Detect(benchmark::State& state) {
  const auto& f = fixture();
  FrameExtractor extractor(f.config);
  ProcessedFrame out;
  size_t i = 0;
  for (auto _ : state) {
    extractor.extract(f.frames[i++ % f.frames.size()], out);
    benchmark::DoNotOptimize(out.features.keypoints.data());
  }
  state.counters["frames/s"] = per_second(static_cast<double>(state.iterations()));
}
BENCHMARK(BM_Detect)->Unit(benchmark::kMillisecond);

void set_pair_rate(benchmark::State& state, const cv::Mat& a, const cv::Mat& b) {
  state.counters["descriptor_pairs/s"] = per_second(static_cast<double>(state.iterations()) * a.rows * b.rows);
}

void BM_Match_Symmetric(benchmark::State& state) {
  const auto& f = fixture();
  const cv::Mat& a = f.processed[0].features.descriptors;
  const cv::Mat& b = f.processed[1].features.descriptors;
  SymmetricMatcher matcher(f.config.matching.ratio);
  std::vector<Match> out;
  for (auto _ : state) {
    matcher.match(a, b, out);
    benchmark::DoNotOptimize(out.data());
  }
  set_pair_rate(state, a, b);
}
BENCHMARK(BM_Match_Symmetric)->Unit(benchmark::kMillisecond);


void BM_BackProject(benchmark::State& state) {
  const auto& f = fixture();
  KeypointBackProjector bp(f.config.camera, f.config.depth);
  KeypointGeometry g;
  PointPairs pairs;
  const MotionPrior prior;
  for (auto _ : state) {
    bp.compute(f.processed[1].features.keypoints, f.frames[1].depth_m, g);
    build_point_pairs(f.matches, f.processed[0].geometry, f.processed[0].times, g, f.processed[1].times, &prior, pairs);
    benchmark::DoNotOptimize(pairs.prev.data());
  }
}
BENCHMARK(BM_BackProject)->Unit(benchmark::kMicrosecond);

void BM_Ransac(benchmark::State& state) {
  const auto& f = fixture();
  RigidRansac ransac(f.config.ransac, SensorNoise{}, f.config.features.max_features);
  measure_ransac(state, ransac, f.pairs.prev, f.pairs.curr);
}
BENCHMARK(BM_Ransac)->Unit(benchmark::kMicrosecond);

void BM_Covariance(benchmark::State& state) {
  const auto& f = fixture();
  PerturbationCovariance cov(f.config.covariance, f.config.features.max_features);
  Matrix6d c;
  std::uint64_t seed = 0;
  for (auto _ : state) {
    Rng rng(seed++);
    benchmark::DoNotOptimize(cov.estimate(f.inlier_prev, f.inlier_curr, f.motion, rng, c));
  }
  state.counters["inliers"] = static_cast<double>(f.inlier_prev.size());
}
BENCHMARK(BM_Covariance)->Unit(benchmark::kMillisecond);

// Whole per-frame pipeline: every stage for one new frame against its predecessor.
void BM_Pipeline(benchmark::State& state) {
  const auto& f = fixture();
  OdometryPipeline pipeline(f.config);
  measure_frames(state, [&](std::size_t i) {
    const auto r = pipeline.process(looped_frame(f.frames, i));
    return r && r->status != Status::Ok;
  });
}
BENCHMARK(BM_Pipeline)->Unit(benchmark::kMillisecond);

// The same frames through the straightforward reproduction of the paper (paper_reproduction.hpp):
// BM_Pipeline's frames/s over this one's is the speed-up.
void BM_PaperReproduction(benchmark::State& state) {
  const auto& f = fixture();
  PaperReproduction reproduction(f.config);
  Eigen::Isometry3d motion;
  Matrix6d covariance;
  measure_frames(state, [&](std::size_t i) {
    const bool ok = reproduction.process(looped_frame(f.frames, i), motion, covariance);
    return i > 0 && !ok;  // the first frame has no pair
  });
}
BENCHMARK(BM_PaperReproduction)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace rgbdo

BENCHMARK_MAIN();
