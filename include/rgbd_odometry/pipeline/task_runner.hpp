#pragma once
// Work that per-frame extraction can split (our extractor's pyramid levels) goes to a
// TaskRunner. The pipeline layer owns no threads (src/README.md): the runtime
// supplies a pool of workers started once (runtime/worker_pool.hpp); without one, the tasks
// run in turn on the calling thread. Tasks write disjoint results, so every split of the
// work gives the same output.
namespace rgbdo {

class TaskRunner {
 public:
  using Task = void (*)(void* context, int index);
  virtual ~TaskRunner() = default;
  // Runs task(context, i) for every i in [0, n), lower indices first to start, and returns
  // when all have finished. An exception from a task is rethrown here, after all finished.
  virtual void run(int n, Task task, void* context) = 0;
};

// run_tasks(runner, n, f): f(i) for i in [0, n), on the runner or (null) in turn here. No
// allocation: f is passed by address.
template <class F>
void run_tasks(TaskRunner* runner, int n, F& f) {
  if (runner == nullptr) {
    for (int i = 0; i < n; ++i) f(i);
    return;
  }
  runner->run(n, [](void* context, int i) { (*static_cast<F*>(context))(i); }, &f);
}

}  // namespace rgbdo
