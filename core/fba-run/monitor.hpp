// fba-run's Monitor: one thread that samples a running task (fba::Task::snapshot()) and hands each
// sample to the watchers registered with it: the console's progress line, the live graph dumps
// (--dot-every, SIGUSR1) and the live-view server. One sampler, so that every view of a run reads
// the same counts and a task is read once per tick however many views there are.
#pragma once

#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "fba/task.hpp"

namespace fba_run {

class Monitor {
 public:
  // Called on the monitor's thread with a sample and the one this watcher was given before (null
  // at its first call: rates are then since the start). Watchers are never called concurrently.
  using Watcher = std::function<void(const fba::RunResult& now, const fba::RunResult* previous)>;
  using Duration = std::chrono::steady_clock::duration;

  // How often a watcher is called. `every` zero: at every tick of start()'s period; Duration::max():
  // only when a sample is requested (request_sample). `at_end`: also once by finish(), with the
  // run's final result and a null previous (rates over the whole run).
  struct Schedule {
    Duration every = Duration::zero();
    bool at_end = true;
  };
  static constexpr Duration kOnRequest = Duration::max();

  // `sample` reads the task: Task::snapshot() in fba-run. Called on the monitor's thread only.
  explicit Monitor(std::function<fba::RunResult()> sample);
  ~Monitor();  // stops without the final call
  Monitor(const Monitor&) = delete;
  Monitor& operator=(const Monitor&) = delete;

  // Before start(): registering while the thread calls the watchers would race with it.
  void watch(Watcher watcher, Schedule schedule);
  void watch(Watcher watcher);  // at every tick and at the end
  // Starts the thread: it samples every `period` (the shortest a watcher is called at), and when
  // asked. Once.
  void start(Duration period);
  // From any thread (SIGUSR1's live dump): a sample as soon as the thread can take it, given to
  // every watcher whatever its schedule. Ignored when not running.
  void request_sample();
  // Stops the thread at once (it is waiting, or finishes the call in progress) and joins it.
  void stop();
  // stop(), then each `at_end` watcher called on this thread with the run's final result.
  void finish(const fba::RunResult& final_result);

 private:
  struct Entry {
    Watcher watcher;
    Schedule schedule;
    std::optional<fba::RunResult> previous;
    std::chrono::steady_clock::time_point due;
  };
  void loop(std::stop_token stop);
  void call(Entry& e, const fba::RunResult& now);

  std::function<fba::RunResult()> sample_;
  std::vector<Entry> entries_;
  Duration period_{};
  std::mutex mutex_;
  std::condition_variable_any wake_;
  bool requested_ = false;  // under mutex_
  std::jthread thread_;
};

}  // namespace fba_run
