// fba-run's state: what the main thread, the signal watcher, the exit handler and the crash handler
// share about the run, and the exit statuses they end it with.
#pragma once

#include <atomic>
#include <chrono>
#include <filesystem>
#include <mutex>
#include <stop_token>
#include <string>
#include <thread>

#include "fba/task.hpp"
#include "fba/task_config.hpp"

namespace fba_run {

namespace fs = std::filesystem;

class Console;
class Monitor;

constexpr int kConfigError = 2;
constexpr int kRuntimeError = 3;

// What the watcher, the exit handler and the crash handler need to know about the run.
struct State {
  std::mutex mutex;                           // orders the task's publication against the first signal
  std::atomic<const char*> phase{"loading"};  // loading, constructing, running
  std::atomic<int> signal{0};                 // the first stop signal
  std::atomic<const char*> signal_phase{nullptr};
  std::atomic<int> signals{0};
  std::atomic<fba::Task*> task{nullptr};  // set once constructed
  fs::path summary;                       // empty without --output-dir
  fba::TaskConfig config;                 // what the summary names (the file before it is loaded)
  std::atomic<bool> returning{false};     // main is returning normally: exit() is expected
  std::atomic<bool> exit_taken{false};    // an unexpected exit() is being handled
  std::atomic<bool> watching{true};
  std::thread watcher;
  fs::path live_dot;                       // graph-live.dot in --output-dir, written on SIGUSR1 and by --dot-every
  std::atomic<Monitor*> monitor{nullptr};  // samples the task while it runs; set and cleared under `mutex`
  std::atomic<Console*> console{nullptr};  // the progress line, which fba-run's own messages go above
  std::stop_source stop;             // the task's RunOptions::stop: reaches constructors too
  std::string run_id;                // summary.json's run_id: which run wrote it
  std::chrono::steady_clock::time_point started = std::chrono::steady_clock::now();
};

// The one State, made on first use and never destroyed: alive for the exit handler.
inline State& state() {
  static State* s = new State;
  return *s;
}

}  // namespace fba_run
