// No heap allocation in the per-frame hot path after warm-up. This binary replaces the C
// allocator's entry points (operator new and OpenCV's allocator both end in them) with
// counting forwards to glibc's own, then replays the bundled real frames: after warm-up,
// the pair stage (matching, back-projection, RANSAC, covariance) and the integration must
// not allocate at all. What feature extraction (OpenCV's detector, undistortPoints) still
// allocates is measured and reported, not asserted (src/README.md).
//
// Not built with the sanitizers: AddressSanitizer owns malloc there.
#include <gtest/gtest.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>

#include "rgbd_odometry/pipeline/integrate.hpp"
#include "rgbd_odometry/pipeline/odometry.hpp"
#include "rgbd_odometry/io/tum_sequence.hpp"
#include "rgbd_odometry/pipeline/keyframes.hpp"
#include "rgbd_odometry/pipeline/pair_estimator.hpp"
#include "rgbd_odometry/pipeline/frame_extractor.hpp"
#include "rgbd_odometry/app/config_file.hpp"
#include "rgbd_odometry/pipeline/detect.hpp"
#include "rgbd_odometry/pipeline/mask.hpp"

extern "C" {
void* __libc_malloc(size_t);
void* __libc_calloc(size_t, size_t);
void* __libc_realloc(void*, size_t);
void* __libc_memalign(size_t, size_t);
void __libc_free(void*);
}

namespace {
std::atomic<long> g_allocations{0};
std::atomic<long> g_bytes{0};
inline void count(size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  g_bytes.fetch_add(static_cast<long>(n), std::memory_order_relaxed);
}
}  // namespace

extern "C" {
void* malloc(size_t n) {
  count(n);
  return __libc_malloc(n);
}
void* calloc(size_t a, size_t b) {
  count(a * b);
  return __libc_calloc(a, b);
}
void* realloc(void* p, size_t n) {
  count(n);
  return __libc_realloc(p, n);
}
void* memalign(size_t alignment, size_t n) {
  count(n);
  return __libc_memalign(alignment, n);
}
void* aligned_alloc(size_t alignment, size_t n) {
  count(n);
  return __libc_memalign(alignment, n);
}
int posix_memalign(void** out, size_t alignment, size_t n) {
  count(n);
  *out = __libc_memalign(alignment, n);
  return *out ? 0 : ENOMEM;
}
void free(void* p) { __libc_free(p); }
}

namespace rgbdo {
namespace {

struct Counter {
  long start_allocations = g_allocations.load(), start_bytes = g_bytes.load();
  long allocations() const { return g_allocations.load() - start_allocations; }
  long bytes() const { return g_bytes.load() - start_bytes; }
};

void* volatile g_escape;

TEST(Allocations, CountingAllocatorSeesAllocations) {
  // The probe itself must work, or a zero below would prove nothing. The pointers escape
  // through a volatile, or the compiler may leave out an allocation freed unused.
  const Counter c;
  auto* p = new std::vector<int>(1000);
  g_escape = p;
  void* q = std::malloc(64);
  g_escape = q;
  std::free(q);
  delete p;
  EXPECT_GE(c.allocations(), 3);
}

TEST(Allocations, OurExtractorAllocatesNothingAfterWarmUp) {
  // GRID_ORB sizes its pyramid, candidate and descriptor buffers once; OpenCV's ORB allocates
  // ~300 times per frame (printed by the test below).
  Config config = load_config(RGBDO_CONFIG_DIR "/tum-fr1.yaml");
  config.features.detector = config.features.descriptor = "GRID_ORB";
  const TumSequence seq = open_tum_sequence(RGBDO_TEST_DATA_DIR);
  std::vector<RgbdFrame> frames;
  for (const auto& ref : seq.frames) frames.push_back(load_tum_frame(ref, config.depth.units_per_m, 640, 480));
  FeatureDetector detector(config.features);
  std::vector<cv::Mat> masks(frames.size());
  for (size_t i = 0; i < frames.size(); ++i)
    build_feature_mask(frames[i].depth_m, config.depth, config.features.border_px, masks[i]);
  Features a, b;  // two frames' worth, as the pipeline keeps them
  long allocations = 0;
  size_t keypoints = 0;
  for (size_t i = 0; i < frames.size(); ++i) {
    Features& out = i % 2 ? a : b;
    const Counter c;
    detector.detect(frames[i].gray, masks[i], out);
    if (i >= 2) allocations += c.allocations();
    keypoints += out.keypoints.size();
  }
  EXPECT_EQ(allocations, 0) << "GRID_ORB allocated after the first two frames";
  EXPECT_EQ(keypoints, frames.size() * static_cast<size_t>(config.features.max_features));
}

TEST(Allocations, PairStageAndIntegrationAllocateNothingAfterWarmUp) {
  const Config config = load_config(RGBDO_CONFIG_DIR "/tum-fr1.yaml");
  const TumSequence seq = open_tum_sequence(RGBDO_TEST_DATA_DIR);
  std::vector<RgbdFrame> frames;  // decoded up front: PNG decoding is not the hot path
  for (const auto& ref : seq.frames) frames.push_back(load_tum_frame(ref, config.depth.units_per_m, 640, 480));

  FrameExtractor extractor(config);
  PairEstimator estimator(config);
  KeyframeTracker keyframes(config);
  ReportedCovariance reported(config.covariance);
  TrajectoryIntegrator integrator;
  ProcessedFrame prev, curr;
  constexpr size_t kWarmUp = 10;
  long pair_allocations = 0, keyframe_allocations = 0, integrate_allocations = 0, extract_allocations = 0,
       extract_bytes = 0;
  int keyframes_made = 0;
  int measured = 0, ok = 0;
  extractor.extract(frames[0], prev);
  for (size_t i = 1; i < frames.size(); ++i) {
    const Counter extract;
    extractor.extract(frames[i], curr);
    const long ea = extract.allocations(), eb = extract.bytes();

    const Counter pair;
    PairResult r = estimator.estimate(prev, curr);
    const long pa = pair.allocations();

    const Counter keyframe;
    keyframes.update(curr, r);
    reported.report(r);  // what goes out, counted with the keyframe's stage
    const long ka = keyframe.allocations();

    const Counter integrate;
    if (r.status == Status::Ok) integrator.add(r.T_prev_curr);
    const long ia = integrate.allocations();

    std::swap(prev, curr);
    ok += r.status == Status::Ok;
    if (i <= kWarmUp) continue;
    ++measured;
    pair_allocations += pa;
    keyframe_allocations += ka;
    keyframes_made += r.keyframe.created;
    integrate_allocations += ia;
    extract_allocations += ea;
    extract_bytes += eb;
  }
  EXPECT_EQ(ok, static_cast<int>(frames.size()) - 1);
  EXPECT_EQ(pair_allocations, 0) << "matching, back-projection, RANSAC or covariance allocated";
  EXPECT_EQ(integrate_allocations, 0);
  // New keyframes too (their slots are sized at construction).
  EXPECT_EQ(keyframe_allocations, 0) << "the keyframe's measurement or a new keyframe allocated";
  EXPECT_GE(keyframes_made, 2) << "the frames after the warm-up made too few keyframes to tell";
  std::printf("feature extraction (OpenCV ORB + undistortPoints) per frame after warm-up: %.1f allocations, %.1f KiB\n",
              static_cast<double>(extract_allocations) / measured,
              static_cast<double>(extract_bytes) / measured / 1024.0);
  RecordProperty("extract_allocations_per_frame", std::to_string(extract_allocations / measured));
}

}  // namespace
}  // namespace rgbdo
