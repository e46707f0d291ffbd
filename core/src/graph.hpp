// Runtime internals: the graph (nodes wired by buffers, run by an executor), the executors'
// interface, the stop's watchdog. Not part of the public API.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <stop_token>
#include <string>
#include <thread>
#include <vector>

#include "buffer.hpp"
#include "fba/task.hpp"
#include "fba/task_config.hpp"
#include "fba/thread_pool.hpp"
#include "fba/view.hpp"
#include "node.hpp"
#include "pi_mutex.hpp"

namespace fba::detail {

// Limits the runtime enforces, documented in docs/task-files.md.
//
// Durations are int64 nanoseconds on the executor's clock; a period or a time-out longer than
// this (about 285 years) means "never within this run". Kept below INT64_MAX so that adding it
// to a steady clock reading cannot overflow.
constexpr double kMaxDurationS = 9e9;
constexpr std::int64_t kNeverNs = INT64_MAX;
// Seconds to nanoseconds, saturating at kNeverNs (NaN and infinity included).
std::int64_t duration_ns(double seconds);
// a + b for non-negative b, saturating at kNeverNs.
inline std::int64_t add_ns(std::int64_t a, std::int64_t b) { return a > kNeverNs - b ? kNeverNs : a + b; }

class Executor {
 public:
  virtual ~Executor() = default;
  virtual void enqueue(Node* n) = 0;
  virtual std::int64_t now_ns() const = 0;
  // Runs until the graph stops; its threads may still be finishing their current call.
  virtual void run() = 0;
  // Joins the threads that return within `grace_s`; the others are detached and left behind
  // (they hold the graph: see Graph::abandoned). False when some were left.
  virtual bool join(double grace_s) = 0;
  // Wakes whatever waits so that it sees the graph's stop flag.
  virtual void wake_all() = 0;
  // Wakes the run loop to look at the graph's state (idle, stop).
  virtual void poke() = 0;
};

class Graph {
 public:
  // Wires the graph; components are created by construct(), once every port is connected, so
  // that a component sees its final connections in its constructor.
  Graph(const TaskConfig& config, RunOptions options);
  ~Graph();
  // Creates every component; throws ConfigError when one refuses its configuration.
  void construct();

  void notify(Node* n);
  void run_strand(Node* n);
  // Called by executors whenever no node is queued or running.
  void check_idle();
  void request_stop(Outcome outcome, const std::string& reason, std::shared_ptr<const Event> event = {});
  bool stopping() const { return stopping_.load(std::memory_order_acquire); }
  // Requested by request_stop() and by RunOptions::stop: what Context::stop_token() hands out.
  std::stop_token stop_token() const { return stop_source_.get_token(); }
  std::int64_t now_ns() const { return executor_->now_ns(); }
  // Logs at warn level what the run waits for when nothing has been produced for a while.
  void warn_stall(double quiet_s);
  void record_event(const Event& e);
  void record_event(std::shared_ptr<const Event> e);
  void deliver(const EventRule& rule, const std::shared_ptr<const Event>& e, const Header& header);
  // The node's periodic ticks are over (finished, or its next tick would never come).
  void end_ticks(Node* n);
  std::vector<Packet>& tap(const std::string& port, std::size_t keep = SIZE_MAX);
  std::shared_ptr<LatestSample> watch(const std::string& port, std::size_t keep);
  // Created on first use, with as many threads as the executor has workers.
  ThreadPool& thread_pool();
  RunResult run();
  // The counts and states as they stand, from any thread while the task runs.
  RunResult snapshot();
  std::uint64_t collect_stats(RunResult& r);  // see graph.cpp
  void emergency_safe_states() noexcept;
  std::string safe_states_so_far() const;
  std::vector<Event> events();
  std::string stop_reason() {
    std::lock_guard lock(result_mutex_);
    return result_.reason;
  }

  const TaskConfig config;  // a copy: the graph's strings and rules point into it
  RunOptions options;
  std::filesystem::path task_dir;
  std::vector<std::unique_ptr<Node>> nodes;
  std::vector<std::unique_ptr<Buffer>> buffers;  // destroyed before the nodes (and their libraries)
  std::deque<std::vector<Packet>> taps;
  std::vector<std::shared_ptr<LatestSample>> watches;  // outputs deliver into them: kept while the graph is
  std::unique_ptr<Executor> executor_;
  std::atomic<int> active{0};  // nodes queued or running
  std::atomic<std::uint64_t> notifications{0};  // Idle -> Queued transitions, for check_idle
  std::atomic<int> live_periodic{0};
  // Invocations that emitted something, summed over the nodes (each counts its own: one shared
  // atomic was a locked add on every hop): for the stall warning.
  std::uint64_t progress() const {
    std::uint64_t n = 0;
    for (const auto& node : nodes) n += node->productive_calls;
    return n;
  }
  // Threads were left behind in a component call: the graph must outlive them, so the Task
  // leaks it on purpose rather than destroy what they use.
  std::atomic<bool> abandoned{false};
  std::chrono::steady_clock::time_point constructing_since;  // set by construct(), before `started`
  std::chrono::steady_clock::time_point started;              // run() began
  double construct_s = 0;
  double timeout_s = 0;
  int worker_threads = 2;

 private:
  PiMutex pool_mutex_;
  std::unique_ptr<ThreadPool> pool_;
  Node& node(const std::string& name);
  OutputState& output(const std::string& port, const char* what);  // "component.output"; `what` for the message
  // After the executor stopped: interrupts, joins within the grace, and safe states; returns
  // the calls that did not return.
  std::vector<StuckCall> stop();
  // After a constructor refused its configuration: the constructed actuators' safe states, one
  // result per actuator of the task.
  std::vector<SafeStateResult> safe_states_after_construction();
  // The stop grace, saturated where adding it to the clock would overflow (kMaxDurationS: never).
  std::chrono::steady_clock::duration grace() const;
  std::atomic<bool> stopping_{false};
  std::stop_source stop_source_;
  std::atomic<bool> constructed_{false};
  std::optional<std::stop_callback<std::function<void()>>> external_stop_;  // RunOptions::stop
  // The whole wall time so far: from construct() (or run(), for a graph never constructed).
  double wall_s_now() const;
  PiMutex result_mutex_;  // events are recorded from workers
  RunResult result_;
  // Each event is stored once; the final event is one of them (or, past the list's bound, its own).
  std::vector<std::shared_ptr<const Event>> events_;
  std::shared_ptr<const Event> final_event_;
  std::vector<SafeStateResult> safe_states_;
  bool ran_ = false;
  std::atomic<bool> running_since_set_{false};  // `started` is set: snapshots from other threads may read it
};

// Calls made on threads of their own so that one that never returns cannot hang the stop: the
// caller waits for them up to a deadline, and those still running are left behind (detached).
class Watchdog {
 public:
  Watchdog() = default;
  Watchdog(const Watchdog&) = delete;
  Watchdog& operator=(const Watchdog&) = delete;
  ~Watchdog();                          // joins the calls that returned; detaches the others
  void start(std::function<void()> f);  // runs f inline if no thread can be created
  void wait_until(std::chrono::steady_clock::time_point deadline);
  bool returned(std::size_t i);

 private:
  struct Shared {
    std::mutex mutex;
    std::condition_variable cv;
    std::vector<char> done;
  };
  std::shared_ptr<Shared> shared_ = std::make_shared<Shared>();
  std::vector<std::thread> threads_;
};

// Gives the calling thread an alternate signal stack, so that a crash handler can run even
// when a component overflowed its stack (fba-run installs the handler).
void prepare_thread_for_crash_reports();

std::unique_ptr<Executor> make_threaded_executor(Graph& g, int threads);
std::unique_ptr<Executor> make_deterministic_executor(Graph& g);

}  // namespace fba::detail
