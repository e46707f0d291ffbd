// Building and running a task: the runtime's entry point for fba-run, tests and embedding.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <stop_token>
#include <string>
#include <utility>
#include <vector>

#include "fba/packet.hpp"
#include "fba/task_config.hpp"

namespace fba {

namespace detail {
class Graph;
}
class LatestSample;  // fba/view.hpp

enum class Outcome { Success, Failure, ConfigError, RuntimeError, Interrupted };
const char* to_string(Outcome o);
// fba-run's exit status: 0 success, 1 failure event, 2 configuration error, 3 runtime error
// (including a timeout, a stall or a component that did not return after the stop), 130
// interrupted (143 when by SIGTERM: see RunResult::signal).
int exit_code(Outcome o);

// Thread limits, documented in docs/task-files.md: past them the system runs out of threads, and
// a run that fails half-started is worse than one refused before it starts.
constexpr int kMaxThreads = 256;                    // worker threads of the threaded executor
constexpr std::size_t kMaxDedicatedThreads = 1024;  // components with a thread of their own

struct RunOptions {
  std::optional<ExecutorKind> executor;  // overrides the task file
  int threads = 0;                       // overrides the task file; 0 keeps it; at most kMaxThreads
  std::filesystem::path output_dir;      // artefacts; empty for none
  double timeout_s = 0;                  // 0: no limit; beyond 9e9 s (or not finite), no limit either
  // After a stop: how long running components get to return (after interrupt()), and how long
  // each actuator's safe_state() gets. A call still running then is reported and left behind.
  double stop_grace_s = 5;
  // A warning names what the run waits for when no component has produced anything this long.
  // The deterministic executor, whose clock nothing outside the run moves, instead ends the run as
  // stalled once 60 times this of task time has passed with only timers firing.
  double stall_warning_s = 10;
  // A stop requested through this token (fba-run's signal watcher) stops the task in order, also
  // while its components are being constructed: the constructor running then sees it through
  // Context::stop_token(), the rest are not constructed, and run() only takes the safe states.
  std::stop_token stop;
};

// The time a component spent in one of its stages (Stages).
struct StageTime {
  std::uint64_t entered = 0;  // times it moved into the stage; the first stage counts its start
  double busy_s = 0;          // wall time inside process() while in the stage: where its work went
  double clock_s = 0;         // time on the task's clock in the stage, waits included (virtual under deterministic)
};

struct ComponentStats {
  std::string name, type;
  Kind kind = Kind::Filter;
  std::uint64_t invocations = 0, samples_in = 0, samples_out = 0, errors = 0, restarts = 0;
  std::uint64_t lost_to_restarts = 0;  // input samples taken by invocations that failed and restarted
  std::string stage;
  std::vector<std::pair<std::string, StageTime>> stages;  // in the spec's order; empty without stages
  std::map<std::string, std::string> results;             // Context::report: name -> JSON text
  std::string state;  // idle, queued, running or finished (as it stood when the counts were read)
};

// A component call that had not returned when the run ended: its thread was left behind.
struct StuckCall {
  std::string component, type, call;  // call: "process()", "safe_state()", ...
};

// What an actuator's safe_state() did at the end of the run.
struct SafeStateResult {
  std::string component;
  std::string status;  // "reached", "failed", "did not return", "not constructed" ("not attempted": a forced exit)
  std::string message;
};

// A component's constructor failed while the task was built (Task's constructor): it refused its
// configuration (outcome ConfigError), or its device failed (DeviceError: outcome RuntimeError).
// The actuators constructed before it were sent to their safe states, with these results, one per
// actuator of the task ("not constructed" for those that never were).
class ConstructionError : public ConfigError {
 public:
  ConstructionError(std::vector<Diagnostic> diagnostics, std::vector<SafeStateResult> safe_states,
                    Outcome outcome = Outcome::ConfigError)
      : ConfigError(std::move(diagnostics)), safe_states_(std::move(safe_states)), outcome_(outcome) {}
  const std::vector<SafeStateResult>& safe_states() const { return safe_states_; }
  Outcome outcome() const { return outcome_; }

 private:
  std::vector<SafeStateResult> safe_states_;
  Outcome outcome_;
};

struct ConnectionStats {
  std::string from, to;  // "component.port"
  BufferPolicy policy = BufferPolicy::Lossless;
  // Every sample pushed was delivered (taken by the receiving component), dropped by the
  // buffer's policy, or left in the queue when the run stopped: pushed = delivered + dropped + left.
  std::uint64_t pushed = 0, delivered = 0, dropped = 0, left = 0;
  std::uint64_t peak = 0, peak_bytes = 0;  // the most samples and payload bytes queued at once
  std::size_t capacity = 0;                 // the queue's capacity (1 for latest)
};

struct RunResult {
  Outcome outcome = Outcome::Success;
  std::string reason;
  std::optional<Event> final_event;
  std::optional<std::size_t> final_event_index;  // its place in `events`, when it is listed there
  double wall_s = 0;       // from the first constructor to the end of the stop
  double construct_s = 0;  // of which in the components' constructors
  double run_s() const { return wall_s - construct_s; }  // what rates are counted over
  std::vector<ComponentStats> components;
  std::vector<ConnectionStats> connections;
  std::vector<Event> events;  // every event emitted, in order (bounded: the first 10000)
  std::vector<StuckCall> stuck;
  std::vector<SafeStateResult> safe_states;
  std::uint64_t lost_to_restarts = 0;  // the components' total
  std::string phase;                   // where fba-run was when it ended: loading, constructing, running
  int signal = 0;                      // the signal that interrupted the run, if any: its exit status is 128 + signal
  bool forced = false;                 // a second signal ended the run without waiting for the stop
  std::string run_id;                  // who ran it (fba-run's --run-id), so a summary names its run
  std::vector<std::string> artefacts;  // the files this run wrote into its output folder (fba-run lists them)
  int exit_code() const {
    return outcome == Outcome::Interrupted && signal > 0 ? 128 + signal : fba::exit_code(outcome);
  }
};

// The component call running on the calling thread, for crash and exit reports; null fields
// when none. Async-signal-safe: it only reads a thread-local pointer.
struct ActiveCall {
  const char* component = nullptr;
  const char* type = nullptr;
  const char* call = nullptr;
};
ActiveCall active_call() noexcept;

// The task graph as Graphviz DOT with what a running task shows: each component's state, stage,
// calls and rate; each connection's queue fill, delivery rate and drops (GStreamer's pipeline
// dumps). Rates are since `earlier` (a previous snapshot), or since the start without one.
std::string to_dot(const TaskConfig& task, const RunResult& now, const RunResult* earlier = nullptr);

// fba-run --check's construction: every filter of the task constructed, as a run would, and
// destroyed again; sensors, actuators and blocking types, which own devices, are not. Throws
// ConfigError listing what the constructors said (a handle missing from the spec, a refused
// configuration). See core/src/construction_check.cpp for why only filters.
void check_construction(const TaskConfig& config);

// summary.json: outcome, final event, wall time, per-component counts and rates.
std::string summary_json(const RunResult& result, const TaskConfig& task);

class Task {
 public:
  // Creates every component (their constructors run here, before any thread starts).
  // Throws ConfigError when a component refuses its configuration.
  explicit Task(const TaskConfig& config, RunOptions options = {});
  ~Task();
  Task(const Task&) = delete;
  Task& operator=(const Task&) = delete;

  // Records the samples leaving "component.output" without holding the producer back: all of
  // them, or only the newest `keep` (a test that needs the final model need not hold every
  // intermediate one). Call before run(); read after.
  const std::vector<Packet>& tap(const std::string& port, std::size_t keep = SIZE_MAX);
  // The newest sample leaving "component.output", for a reader on another thread while run()
  // runs (a live view); never holds the producer back. With `keep` > 1, every sample not taken
  // yet, at most `keep` (see LatestSample). Call before run(); each call makes its own.
  std::shared_ptr<LatestSample> watch(const std::string& port, std::size_t keep = 1);

  // Runs to the end; the result says how it ended. May be called once.
  RunResult run();
  // From any thread (signal watcher, a test): stop in order with this outcome.
  void request_stop(Outcome outcome, const std::string& reason);
  // Last resort after a crash, on the crashing thread: calls safe_state() on every constructed
  // actuator whose safe state was not attempted yet, catching everything. Not async-signal-safe
  // (components run arbitrary code): best effort.
  void emergency_safe_states() noexcept;
  // The actuators' safe states so far, for a forced exit's message: "name (status)", ...
  std::string safe_states_so_far() const;
  // The counts, states and queue fills as they stand, from any thread while run() runs (for
  // live graph dumps and a forced exit's summary); `left` is what is queued now, `stuck` the
  // component calls running now, `safe_states` the actuators' so far. The run's own result is run()'s.
  RunResult snapshot() const;

 private:
  std::unique_ptr<detail::Graph> graph_;
};

}  // namespace fba
