// The extraction's worker pool (runtime/worker_pool.hpp): every task once per call, on as
// many calls as a run makes, an exception from any thread back to the caller after all
// tasks finished, and GRID_ORB's output the same bit for bit with helpers as without.
#include <gtest/gtest.h>

#include <atomic>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <vector>

#include "rgbd_odometry/app/config_file.hpp"
#include "rgbd_odometry/io/tum_sequence.hpp"
#include "rgbd_odometry/pipeline/grid_orb.hpp"
#include "rgbd_odometry/pipeline/mask.hpp"
#include "rgbd_odometry/runtime/worker_pool.hpp"

namespace rgbdo {
namespace {

TEST(WorkerPool, RunsEveryTaskExactlyOncePerCall) {
  for (int workers : {0, 1, 3}) {
    WorkerPool pool(workers);
    EXPECT_EQ(pool.workers(), workers);
    for (int call = 0; call < 200; ++call) {
      const int n = call % 13;  // 0 tasks included
      std::vector<std::atomic<int>> runs(static_cast<size_t>(n));
      auto task = [&](int i) { runs[static_cast<size_t>(i)].fetch_add(1); };
      run_tasks(&pool, n, task);
      for (int i = 0; i < n; ++i) ASSERT_EQ(runs[static_cast<size_t>(i)].load(), 1) << workers << " workers, call " << call;
    }
  }
}

TEST(WorkerPool, AnExceptionReachesTheCallerAfterEveryTaskFinished) {
  WorkerPool pool(3);
  for (int failing : {0, 5, 9}) {
    std::atomic<int> finished{0};
    auto task = [&](int i) {
      if (i == failing) throw std::runtime_error("task " + std::to_string(i) + " failed");
      finished.fetch_add(1);
    };
    try {
      run_tasks(&pool, 10, task);
      FAIL() << "no exception from task " << failing;
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(std::string(e.what()), "task " + std::to_string(failing) + " failed");
    }
    EXPECT_EQ(finished.load(), 9);  // the others all ran, and had finished
  }
  // The pool keeps working after a failure.
  std::atomic<int> count{0};
  auto task = [&](int) { count.fetch_add(1); };
  run_tasks(&pool, 20, task);
  EXPECT_EQ(count.load(), 20);
}

TEST(WorkerPool, GridOrbFindsTheSameFeaturesWithHelpers) {
  const Config config = load_config(RGBDO_CONFIG_DIR "/tum-fr1.yaml");
  const TumSequence seq = open_tum_sequence(RGBDO_TEST_DATA_DIR);
  WorkerPool pool(3);
  GridOrbExtractor alone(config.features, 640, 480), helped(config.features, 640, 480, &pool);
  for (size_t i : {0u, 13u, 27u}) {
    const RgbdFrame f = load_tum_frame(seq.frames[i], config.depth.units_per_m, 640, 480);
    cv::Mat mask;
    build_feature_mask(f.depth_m, config.depth, config.features.border_px, mask);
    Features a, b;
    alone.detect(f.gray, mask, a);
    helped.detect(f.gray, mask, b);
    ASSERT_GT(a.keypoints.size(), 900u);
    ASSERT_EQ(a.keypoints.size(), b.keypoints.size());
    for (size_t k = 0; k < a.keypoints.size(); ++k) {
      EXPECT_EQ(a.keypoints[k].pt, b.keypoints[k].pt) << "frame " << i << " keypoint " << k;
      EXPECT_EQ(a.keypoints[k].angle, b.keypoints[k].angle);
      EXPECT_EQ(a.keypoints[k].octave, b.keypoints[k].octave);
    }
    EXPECT_EQ(cv::norm(a.descriptors, b.descriptors, cv::NORM_HAMMING), 0) << "frame " << i;
  }
}

}  // namespace
}  // namespace rgbdo
