// The task's threads for data-parallel work inside components (carving, rendering). One pool per
// task, sized like the executor, reached as ctx.thread_pool(): components share the cores with
// the runtime instead of each starting a thread per core.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "fba/parallel_for.hpp"

namespace fba {

class ThreadPool {
 public:
  // `threads` workers besides the callers (at least one).
  explicit ThreadPool(int threads);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  // Calls fn(i) for every i in [0, n), on the pool's threads and the calling one, and returns
  // when all are done. The first exception thrown is rethrown here (the remaining indices are
  // skipped). Safe to call from several threads at once, and from inside fn.
  void parallel_for(std::size_t n, const std::function<void(std::size_t)>& fn);
  // parallel_for() as the type library code takes; the pool must outlive it.
  ParallelFor as_parallel_for() {
    return [this](std::size_t n, const std::function<void(std::size_t)>& fn) { parallel_for(n, fn); };
  }
  int size() const { return static_cast<int>(workers_.size()); }

 private:
  struct Job;
  void worker();
  static void work_on(Job& job);

  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::shared_ptr<Job>> jobs_;  // with indices left to hand out
  bool stopping_ = false;
  std::vector<std::thread> workers_;
};

}  // namespace fba
