// Shared helpers of the runtime's tests: a registry with the example plugin and the test
// components, and a loader for inline task text and what it says.
#pragma once

#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <string>
#include <vector>

#include <fba/registry.hpp>
#include <fba/task.hpp>
#include <fba/task_config.hpp>

namespace fba::test {

const Registry& registry();
TaskConfig load(const std::string& yaml, const LoadOptions& options = {});
std::vector<std::int64_t> ints(const std::vector<Packet>& packets);

// What loading `yaml` as test.yaml says (ConfigError's text); empty when it loads.
std::string errors_of(const std::string& yaml, const LoadOptions& options = {});
// The diagnostics of loading the task file `file`; none when it loads.
std::vector<Diagnostic> diagnostics_of_file(const std::filesystem::path& file, const LoadOptions& options = {});
// Those diagnostics as text, a line each.
std::string errors_of_file(const std::filesystem::path& file);

// A flag one thread raises and another waits for: a blocking component's release.
class Flag {
 public:
  void raise() {
    {
      std::lock_guard lock(mutex_);
      raised_ = true;
    }
    cv_.notify_all();
  }
  void wait() {
    std::unique_lock lock(mutex_);
    cv_.wait(lock, [this] { return raised_; });
  }
  // Whether it was raised within `timeout`.
  bool wait_for(std::chrono::nanoseconds timeout) {
    std::unique_lock lock(mutex_);
    return cv_.wait_for(lock, timeout, [this] { return raised_; });
  }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  bool raised_ = false;
};

// A chain that loads: a counter of 5, a passthrough and a sink.
inline constexpr const char* kChain = R"(
components:
  source: { type: examples.counter, params: { count: 5 } }
  pass: { type: examples.passthrough }
  sink: { type: examples.sink }
connections:
  - source.out -> pass.in
  - pass.out -> sink.in
)";

// Options for a test run on the given executor, with a timeout as a safety net (never a bound).
inline RunOptions with(ExecutorKind e, double timeout_s = 60) {
  RunOptions o;
  o.executor = e;
  o.timeout_s = timeout_s;
  return o;
}

// Whether the run recorded event `name` from `source`, its payload containing `payload_part`.
inline bool has_event(const RunResult& r, const std::string& source, const std::string& name,
                      const std::string& payload_part = "") {
  for (const auto& e : r.events)
    if (e.source == source && e.name == name && e.payload.find(payload_part) != std::string::npos) return true;
  return false;
}

}  // namespace fba::test
