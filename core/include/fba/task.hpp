// Building and running a task: the runtime's entry point for fba-run, tests and embedding.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fba/packet.hpp"
#include "fba/task_config.hpp"

namespace fba {

namespace detail {
class Graph;
}

enum class Outcome { Success, Failure, ConfigError, RuntimeError, Interrupted };
const char* to_string(Outcome o);
// fba-run's exit status: 0 success, 1 failure event, 2 configuration error, 3 runtime error
// (including a timeout or a stall), 130 interrupted.
int exit_code(Outcome o);

struct RunOptions {
  std::optional<ExecutorKind> executor;  // overrides the task file
  int threads = 0;                       // overrides the task file; 0 keeps it
  std::filesystem::path output_dir;      // artefacts; empty for none
  double timeout_s = 0;                  // 0: no limit; beyond 9e9 s (or not finite), no limit either
};

struct ComponentStats {
  std::string name, type;
  Kind kind = Kind::Filter;
  std::uint64_t invocations = 0, samples_in = 0, samples_out = 0, errors = 0, restarts = 0;
  std::string stage;
};

struct ConnectionStats {
  std::string from, to;  // "component.port"
  BufferPolicy policy = BufferPolicy::Lossless;
  // Every sample pushed was delivered (taken by the receiving component), dropped by the
  // buffer's policy, or left in the queue when the run stopped: pushed = delivered + dropped + left.
  std::uint64_t pushed = 0, delivered = 0, dropped = 0, left = 0;
  std::uint64_t peak = 0, peak_bytes = 0;  // the most samples and payload bytes queued at once
};

struct RunResult {
  Outcome outcome = Outcome::Success;
  std::string reason;
  std::optional<Event> final_event;
  std::optional<std::size_t> final_event_index;  // its place in `events`, when it is listed there
  double wall_s = 0;
  std::vector<ComponentStats> components;
  std::vector<ConnectionStats> connections;
  std::vector<Event> events;  // every event emitted, in order (bounded: the first 10000)
  int exit_code() const { return fba::exit_code(outcome); }
};

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

  // Runs to the end; the result says how it ended. May be called once.
  RunResult run();
  // From any thread (signal watcher, a test): stop in order with this outcome.
  void request_stop(Outcome outcome, const std::string& reason);

 private:
  std::unique_ptr<detail::Graph> graph_;
};

}  // namespace fba
