#pragma once
// The extraction's helpers (runtime.extraction_threads - 1 worker threads, started once with
// the run): a TaskRunner (pipeline/task_runner.hpp) whose caller works too, taking task
// indices from a shared counter in order. A task that throws does not take its thread, or
// the process, down: the first exception is rethrown to the caller of run() once every task
// of that call has finished.
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "rgbd_odometry/pipeline/task_runner.hpp"

namespace rgbdo {

class WorkerPool final : public TaskRunner {
 public:
  // `workers` threads besides the caller's (0: run() does everything itself). on_start runs
  // first in each worker (e.g. to pin it to a CPU); it must not throw.
  explicit WorkerPool(int workers, const std::function<void(int worker)>& on_start = {});
  ~WorkerPool() override;
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  void run(int n, Task task, void* context) override;
  int workers() const { return static_cast<int>(threads_.size()); }

 private:
  void work(int worker, const std::function<void(int)>& on_start);
  void take_tasks();  // runs tasks until the counter passes n

  std::mutex mutex_;
  std::condition_variable wake_, finished_;
  std::vector<std::thread> threads_;
  // The current call's work: written under mutex_ before the generation changes.
  Task task_ = nullptr;
  void* context_ = nullptr;
  int n_ = 0;
  std::atomic<int> next_{0};
  std::uint64_t generation_ = 0;
  int busy_ = 0;  // workers still in the current generation
  bool stopping_ = false;
  std::exception_ptr error_;
};

}  // namespace rgbdo
