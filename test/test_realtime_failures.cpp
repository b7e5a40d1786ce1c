// A failure inside a thread of the real-time pipeline ends the run, never the process: a
// source whose read throws (the capture thread), an output consumer that throws (the output
// thread); each run stops with the failure named, after outputting what was finished, and
// the frames before the failure are all there. A frame the pipeline cannot take (wrong image
// types) is a flagged frame, not an exception. The recorded frames are real (bundled TUM).
#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <string>
#include <vector>

#include "rgbd_odometry/app/config_file.hpp"
#include "rgbd_odometry/runtime/realtime.hpp"
#include "rgbd_odometry/sensor/frame_feed.hpp"

namespace rgbdo {
namespace {

// The bundled recording, with a fault at frame `at`: the read throws, or the frame's images
// come with the wrong types.
class FaultyFeed final : public FrameFeed {
 public:
  enum class Fault { Throw, WrongTypes };
  FaultyFeed(const Config& config, int at, Fault fault)
      : inner_(open_frame_feed("tum:" RGBDO_TEST_DATA_DIR, config, config.sensor, 0)), at_(at), fault_(fault) {}
  FeedState next(RgbdFrame& frame, std::string& problem) override {
    const FeedState state = inner_->next(frame, problem);
    if (state == FeedState::Frame && read_++ == at_) {
      if (fault_ == Fault::Throw) throw std::runtime_error("the source broke at frame " + std::to_string(at_));
      frame.gray.convertTo(frame.gray, CV_16U);
    }
    return state;
  }
  bool live() const override { return false; }
  void interrupt() override { inner_->interrupt(); }
  std::string description() const override { return "faulty " + inner_->description(); }

 private:
  std::unique_ptr<FrameFeed> inner_;
  int read_ = 0;
  const int at_;
  const Fault fault_;
};

Config config_with_threads(int processing_threads) {
  Config c = load_config(RGBDO_CONFIG_DIR "/tum-fr1.yaml");
  c.runtime.processing_threads = processing_threads;
  c.runtime.extraction_threads = 2;
  return c;
}

TEST(RealtimeFailures, AThrowingSourceStopsTheRunWithItsNameAndKeepsWhatCameBefore) {
  for (int threads : {1, 2}) {
    const Config config = config_with_threads(threads);
    FaultyFeed feed(config, 12, FaultyFeed::Fault::Throw);
    std::vector<PairOutput> outputs;
    RealtimePipeline pipeline(config, config.runtime, feed, [&](const PairOutput& o) { outputs.push_back(o); }, [](const std::string&) {});
    const std::atomic<bool> never{false};
    const RealtimeStats stats = pipeline.run(never);
    EXPECT_EQ(stats.failure, "capture thread: the source broke at frame 12") << threads << " processing threads";
    // Recordings are read losslessly: the 12 frames read before the failure were all output,
    // in order, 11 pairs of them ok.
    ASSERT_EQ(outputs.size(), 12u);
    EXPECT_EQ(stats.frames, 12u);
    int ok = 0;
    for (const auto& o : outputs) ok += o.has_pair && o.result.status == Status::Ok;
    EXPECT_EQ(ok, 11);
  }
}

TEST(RealtimeFailures, AThrowingOutputStopsTheRunInsteadOfTheProcess) {
  const Config config = config_with_threads(2);
  FaultyFeed feed(config, 1000, FaultyFeed::Fault::Throw);  // no fault from the source
  int seen = 0;
  RealtimePipeline pipeline(
      config, config.runtime, feed,
      [&](const PairOutput&) {
        if (++seen == 5) throw std::runtime_error("the log's disk is gone");
      },
      [](const std::string&) {});
  const std::atomic<bool> never{false};
  const RealtimeStats stats = pipeline.run(never);
  EXPECT_EQ(stats.failure, "output thread: the log's disk is gone");
  EXPECT_EQ(seen, 5);  // nothing after the failure reached the broken consumer
}

TEST(RealtimeFailures, AFrameOfTheWrongTypesIsFlaggedAndTrackingResumes) {
  const Config config = config_with_threads(2);
  FaultyFeed feed(config, 7, FaultyFeed::Fault::WrongTypes);
  std::vector<PairOutput> outputs;
  RealtimePipeline pipeline(config, config.runtime, feed, [&](const PairOutput& o) { outputs.push_back(o); }, [](const std::string&) {});
  const std::atomic<bool> never{false};
  const RealtimeStats stats = pipeline.run(never);
  EXPECT_EQ(stats.failure, "");
  ASSERT_EQ(outputs.size(), 40u);
  EXPECT_EQ(outputs[7].result.status, Status::BadFrame);
  EXPECT_NE(outputs[7].frame_problem.find("16UC1"), std::string::npos) << outputs[7].frame_problem;
  EXPECT_EQ(outputs[8].result.status, Status::BadFrame);  // its predecessor was bad
  for (size_t i = 9; i < outputs.size(); ++i) EXPECT_EQ(outputs[i].result.status, Status::Ok) << "frame " << i;
}

}  // namespace
}  // namespace rgbdo
