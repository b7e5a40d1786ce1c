#include "rgbd_odometry/runtime/realtime.hpp"

#include <pthread.h>
#include <sched.h>

#include <chrono>
#include <iomanip>
#include <mutex>
#include <sstream>
#include <thread>
#include <vector>

#include "rgbd_odometry/core/clock.hpp"
#include "rgbd_odometry/runtime/bounded_queue.hpp"
#include "rgbd_odometry/runtime/frame_mailbox.hpp"
#include "rgbd_odometry/runtime/worker_pool.hpp"
#include "rgbd_odometry/pipeline/capture_latency.hpp"
#include "rgbd_odometry/pipeline/pair_estimator.hpp"
#include "rgbd_odometry/pipeline/frame_extractor.hpp"
#include "rgbd_odometry/pipeline/keyframes.hpp"
#include "rgbd_odometry/pipeline/reported_covariance.hpp"

namespace rgbdo {
namespace {

using Clock = std::chrono::steady_clock;
constexpr auto kPoll = std::chrono::milliseconds(50);  // bound of every wait that must notice a stop
constexpr auto kStatusPeriod = std::chrono::seconds(10);
constexpr std::size_t kProcessedSlots = 4;  // previous + current (estimation), one extracting, one ready
constexpr std::size_t kOutputDepth = 64;

struct ProcessedSlot {
  ProcessedFrame frame;
  std::int64_t t_capture_host_ns = 0;
  int skipped_before = 0;
  bool after_gap = false;
  double detect_ms = 0;
};

void check_cpus_allowed(const std::vector<int>& cpus) {
  cpu_set_t allowed;
  CPU_ZERO(&allowed);
  if (sched_getaffinity(0, sizeof allowed, &allowed) != 0) return;
  for (const int cpu : cpus)
    if (cpu >= CPU_SETSIZE || !CPU_ISSET(cpu, &allowed))
      throw ConfigError("config key 'runtime.cpu_affinity': CPU " + std::to_string(cpu) +
                        " is not available to this process (this machine has " +
                        std::to_string(std::thread::hardware_concurrency()) + " CPUs)");
}

// Pins the calling thread to the role's CPU (roles: 0 capture, 1 extraction, 2 estimation, 3 output,
// 4.. extraction helpers).
void pin_thread(const std::vector<int>& cpus, int role) {
  if (cpus.empty()) return;
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpus[static_cast<size_t>(role) % cpus.size()], &set);
  pthread_setaffinity_np(pthread_self(), sizeof set, &set);  // checked up front by check_cpus_allowed
}

// One run's shared state; every thread function is a member.
class Run {
 public:
  Run(const PipelineConfig& config, const RuntimeConfig& runtime, FrameFeed& feed, GyroFeed* gyro,
      const RealtimePipeline::OutputFn& on_output,
      const RealtimePipeline::MessageFn& on_message, const std::function<void()>& on_tick)
      : on_tick_(on_tick), config_(config), runtime_(runtime), cpus_(parse_cpu_list(runtime.cpu_affinity)), feed_(feed),
        on_output_(on_output),
        on_message_(on_message),
        mailbox_(!feed.live()),
        pool_(runtime.extraction_threads > 1
                  ? std::make_unique<WorkerPool>(runtime.extraction_threads - 1,
                                                 [this](int worker) { pin_thread(cpus_, 4 + worker); })
                  : nullptr),
        extractor_(config, pool_.get()),
        estimator_(config),
        keyframes_(config),
        reported_(config.covariance),
        capture_clock_(config, gyro) {
    check_cpus_allowed(cpus_);
    for (std::size_t i = 0; i < kProcessedSlots; ++i) free_.push(static_cast<int>(i));
  }

  RealtimeStats go(const std::atomic<bool>& stop) {
    std::vector<std::thread> threads;
    threads.emplace_back([this] { guarded(Role::Capture, [this] { capture(); }); });
    if (runtime_.processing_threads == 2) {
      threads.emplace_back([this] { guarded(Role::Extraction, [this] { extraction(); }); });
      threads.emplace_back([this] { guarded(Role::Estimation, [this] { estimation(); }); });
    } else {
      threads.emplace_back([this] { guarded(Role::Processing, [this] { extract_and_estimate(); }); });
    }
    threads.emplace_back([this] {
      guarded(Role::Output, [this] { output(); });
      output_done_ = true;
    });
    bool stopping = false;
    while (!output_done_) {
      if (stop && !stopping) {
        stopping = true;
        stopping_ = true;
        feed_.interrupt();
        mailbox_.close();  // what is in hand is finished and output; nothing new is taken
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    for (auto& t : threads) t.join();
    stats_.failure = failure_;
    stats_.skipped = mailbox_.skipped();
    stats_.without_depth = static_cast<std::uint64_t>(feed_.frames_without_depth());
    stats_.dropped_by_sensor = feed_.dropped_frames();
    return stats_;
  }

 private:
  // Runs a thread's body. An exception (a corrupt frame deep in OpenCV, a bug) must not take
  // the process down in flight: it is noted with the thread's name and the run stops as at a
  // stop request. The failed thread's own queues are closed, so that the threads upstream
  // stop and the ones downstream finish and output what they already hold; run() then
  // reports it (RealtimeStats::failure).
  enum class Role { Capture, Extraction, Estimation, Processing, Output };
  template <class Body>
  void guarded(Role role, Body body) {
    try {
      body();
    } catch (const std::exception& e) {
      fail(role, e.what());
    } catch (...) {
      fail(role, "an exception of unknown type");
    }
  }
  void fail(Role role, const std::string& what) {
    static constexpr const char* kNames[] = {"capture thread", "extraction thread", "estimation thread",
                                             "processing thread", "output thread"};
    {
      std::lock_guard<std::mutex> lock(messages_mutex_);
      if (failure_.empty()) failure_ = std::string(kNames[static_cast<int>(role)]) + ": " + what;
    }
    stopping_ = true;
    feed_.interrupt();
    mailbox_.close();  // capture stops; a frame in hand is still taken
    if (role == Role::Extraction || role == Role::Estimation || role == Role::Output) ready_.close();
    if (role == Role::Estimation || role == Role::Output) free_.close();
    if (role == Role::Estimation || role == Role::Processing || role == Role::Output) outputs_.close();
  }

  // --- capture thread -------------------------------------------------------------------
  void capture() {
    pin_thread(cpus_, 0);
    bool after_gap = false;
    std::string problem;
    while (!stopping_) {
      CapturedFrame& slot = mailbox_.fill_slot();
      problem.clear();
      const FeedState state = feed_.next(slot.frame, problem);
      if (state == FeedState::End) {
        if (!problem.empty() && !stopping_) message("source ended: " + problem);
        break;
      }
      if (state == FeedState::Lost) {
        ++stats_.sensor_losses;
        message("sensor lost: " + problem);
        std::string why;
        if (!feed_.wait_for_return(stopping_, why)) {
          if (!why.empty() && !stopping_) message(why);
          break;
        }
        ++stats_.reopens;
        message("sensor back: " + feed_.description() + "; odometry restarts (reset)");
        after_gap = true;
        continue;
      }
      // A live frame's timeline is the host steady clock, ahead by its lead (device_clock.hpp).
      slot.t_capture_host_ns = feed_.live() ? slot.frame.host_colour_ns() : steady_now_ns();
      slot.skipped_before = 0;
      slot.after_gap = after_gap;
      after_gap = false;
      if (!mailbox_.publish()) break;
    }
    mailbox_.close();
  }

  // --- processing threads ---------------------------------------------------------------
  void extract_into(const CapturedFrame& in, ProcessedSlot& out) {
    const auto start = Clock::now();
    extractor_.extract(in.frame, out.frame);
    out.detect_ms = ms_since(start);
    out.t_capture_host_ns = in.t_capture_host_ns;
    out.skipped_before = in.skipped_before;
    out.after_gap = in.after_gap;
  }

  void extraction() {
    pin_thread(cpus_, 1);
    while (CapturedFrame* in = mailbox_.take()) {
      const auto slot = free_.pop();
      if (!slot) break;
      extract_into(*in, slots_[static_cast<size_t>(*slot)]);
      ready_.push(*slot);
    }
    ready_.close();
  }

  void estimation() {
    pin_thread(cpus_, 2);
    int prev = -1;
    while (const auto curr = ready_.pop()) {
      if (!estimate(prev, *curr)) {  // a dropped frame: the next one pairs with prev
        free_.push(*curr);
        continue;
      }
      if (prev >= 0) free_.push(prev);
      prev = *curr;
    }
    outputs_.close();
  }

  // runtime.processing_threads = 1: both stages in turn, on one thread.
  void extract_and_estimate() {
    pin_thread(cpus_, 1);
    int prev = -1, curr = 0;
    while (CapturedFrame* in = mailbox_.take()) {
      extract_into(*in, slots_[static_cast<size_t>(curr)]);
      if (!estimate(prev, curr)) continue;  // a dropped frame: its slot is filled again
      prev = curr;
      curr = (curr + 1) % 2;
    }
    outputs_.close();
  }

  // False when the current frame is dropped (its stamp is not after the previous frame's).
  bool estimate(int prev_index, int curr_index) {
    const ProcessedSlot& curr = slots_[static_cast<size_t>(curr_index)];
    PairOutput out;
    out.t_frame_ns = curr.frame.times.t_colour_ns;
    out.t_depth_ns = curr.frame.times.t_depth_ns;
    out.host_lead_ns = curr.frame.times.host_lead_ns;
    out.t_capture_host_ns = curr.t_capture_host_ns;
    out.skipped = curr.skipped_before;
    out.frame_problem = curr.frame.problem;
    if (prev_index >= 0) {
      const ProcessedSlot& prev = slots_[static_cast<size_t>(prev_index)];
      out.has_pair = true;
      if (curr.after_gap) {
        // Whatever moved while the sensor was away is unknown: a failed pair, and no motion
        // prior carried across the gap.
        PairResult& r = out.result;
        // Two timelines (a re-plugged sensor's clock restarts): each frame on the host clock.
        r.t_prev_ns = prev.frame.times.host_colour_ns();
        r.t_curr_ns = curr.frame.times.host_colour_ns();
        r.status = Status::SensorLost;
        r.features_prev = static_cast<int>(prev.frame.features.keypoints.size());
        r.features_curr = static_cast<int>(curr.frame.features.keypoints.size());
        estimator_.forget_motion();
      } else {
        estimator_.set_latency_sigmas(capture_clock_.latency_sigmas());
        out.result = estimator_.estimate(prev.frame, curr.frame);
      }
      if (!PairEstimator::dropped_frame(out.result)) {
        capture_clock_.stamp(out.result);  // from the frame pair's own rotation, before the keyframe's
        keyframes_.update(curr.frame, out.result);
        reported_.report(out.result);  // what goes out, after every use of the pair's own
      }
      out.result.times.detect_ms = curr.detect_ms;
    }
    const bool kept = !(out.has_pair && PairEstimator::dropped_frame(out.result));
    outputs_.push(std::move(out));
    return kept;
  }

  // --- output thread --------------------------------------------------------------------
  void output() {
    pin_thread(cpus_, 3);
    auto next_status = Clock::now() + kStatusPeriod;
    std::uint64_t frames_at_status = 0;
    SensorEstimates learnt;  // as of the last good pair
    CaptureTiming timing;    // as of the last pair
    for (;;) {
      auto item = outputs_.pop_for(kPoll);
      flush_messages();
      if (on_tick_) on_tick_();
      for (std::string news = feed_.news(); !news.empty(); news = feed_.news()) on_message_(news);
      if (item) {
        ++stats_.frames;
        if (item->has_pair && PairEstimator::dropped_frame(item->result)) {
          ++(item->result.status == Status::StampNotIncreasing ? stats_.stamp_not_increasing
                                                               : stats_.bridged_without_depth);
        } else if (item->has_pair) {
          ++stats_.pairs;
          item->latency_ms = static_cast<double>(steady_now_ns() - item->t_capture_host_ns) * 1e-6;
          stats_.latency.add(item->latency_ms);
          if (item->result.status == Status::Ok) learnt = item->result.sensor;
          timing = item->result.timing;
        }
        on_output_(*item);
      } else if (outputs_.closed_and_empty()) {
        break;
      }
      if (feed_.live() && Clock::now() >= next_status) {
        std::ostringstream s;
        s << std::fixed << std::setprecision(1) << "status: " << (stats_.frames - frames_at_status) / 10.0
          << " frames/s, " << mailbox_.skipped() << " skipped, " << feed_.frames_without_depth() << " without depth, "
          << feed_.dropped_frames()
          << " dropped by the sensor, latency median " << stats_.latency.quantile_ms(0.5) << " ms, p99 "
          << stats_.latency.quantile_ms(0.99) << " ms";
        if (learnt.depth_sigma_scale_t > 0) s << "; " << sensor_estimates_text(learnt);
        if (timing.gyro) s << "; " << capture_latency_text(timing);
        on_message_(s.str());
        const BodyConfig& b = config_.body;
        if (const std::string mount = mount_text(timing, b.camera_roll_deg, b.camera_pitch_deg, b.camera_yaw_deg,
                                                 config_.latency.mount_warning_deg);
            !mount.empty())
          on_message_(mount);
        frames_at_status = stats_.frames;
        next_status += kStatusPeriod;
      }
    }
    flush_messages();
  }

  // Messages are raised on the capture thread but printed on the output thread, so that each
  // output stream has a single writer.
  void message(std::string text) {
    std::lock_guard<std::mutex> lock(messages_mutex_);
    messages_.push_back(std::move(text));
  }
  void flush_messages() {
    std::vector<std::string> pending;
    {
      std::lock_guard<std::mutex> lock(messages_mutex_);
      pending.swap(messages_);
    }
    for (const auto& m : pending) on_message_(m);
  }

  const std::function<void()>& on_tick_;
  const PipelineConfig& config_;
  const RuntimeConfig& runtime_;
  const std::vector<int> cpus_;
  FrameFeed& feed_;
  const RealtimePipeline::OutputFn& on_output_;
  const RealtimePipeline::MessageFn& on_message_;
  FrameMailbox mailbox_;
  std::unique_ptr<WorkerPool> pool_;  // the extraction's helpers (before extractor_: outlives it)
  FrameExtractor extractor_;  // the extraction thread's
  PairEstimator estimator_;   // the estimation thread's
  KeyframeTracker keyframes_;  // the estimation thread's
  ReportedCovariance reported_;  // the estimation thread's
  CaptureClock capture_clock_;  // the estimation thread's: when the frames were taken
  std::array<ProcessedSlot, kProcessedSlots> slots_;
  BoundedQueue<int, kProcessedSlots> free_, ready_;
  BoundedQueue<PairOutput, kOutputDepth> outputs_;
  std::atomic<bool> stopping_{false}, output_done_{false};
  std::mutex messages_mutex_;
  std::vector<std::string> messages_;
  std::string failure_;  // the first thread failure (under messages_mutex_)
  RealtimeStats stats_;  // each field has one writing thread; read after the joins
};

}  // namespace

RealtimePipeline::RealtimePipeline(const PipelineConfig& config, const RuntimeConfig& runtime, FrameFeed& feed,
                                   OutputFn on_output, MessageFn on_message, GyroFeed* gyro)
    : config_(config), runtime_(runtime), feed_(feed), gyro_(gyro), on_output_(std::move(on_output)),
      on_message_(std::move(on_message)) {}

RealtimeStats RealtimePipeline::run(const std::atomic<bool>& stop) {
  auto run = std::make_unique<Run>(config_, runtime_, feed_, gyro_, on_output_, on_message_, on_tick_);
  return run->go(stop);
}

}  // namespace rgbdo
