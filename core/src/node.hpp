// Runtime internals: a node (a component and its ports, their states, its events and stages).
// Not part of the public API.
#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "buffer.hpp"
#include "fba/component.hpp"
#include "fba/task.hpp"
#include "fba/task_config.hpp"
#include "pi_mutex.hpp"

namespace fba::detail {

class Graph;

// A limit the runtime enforces, documented in docs/task-files.md.
constexpr std::size_t kMaxEventPayload = 64 * 1024;  // bytes; longer payloads are truncated

// A name that lives as long as the process (headers point to it: a packet may outlive its task).
const std::string* intern_name(std::string_view name);

struct InputState {
  const PortSpec* spec = nullptr;
  Buffer* buffer = nullptr;
  bool closes_node = true;  // false for event inputs: events are not a stream that ends
  Counter received;
  bool closed() const {
    return buffer == nullptr || (buffer->producer_done.load(std::memory_order_seq_cst) && buffer->empty());
  }
};

struct OutputState {
  explicit OutputState(const std::string& producer_name) : producer(producer_name) {}
  const PortSpec* spec = nullptr;
  const TypeInfo* type = nullptr;  // resolved (outputs typed like an input get that type)
  std::vector<Buffer*> consumers;
  const std::string& producer;  // "component.output", interned: every header points to it
  Counter next_seq;
  Node* node = nullptr;
};

class Node {
 public:
  enum State : int { Idle, Queued, Running, RunningNotified };

  Node(Graph& graph, const ComponentConfig& config);
  void construct();  // creates the component; throws

  bool ready() const;
  // One invocation (or the end-of-stream call). Runs on the node's strand only.
  void invoke();
  // Records an event and applies its rules; a payload over kMaxEventPayload is truncated.
  void emit_event(std::string_view name, std::string payload);
  void on_finish();  // marks finished and tells the consumers
  // Calls one of the component's methods, catching everything: the message of what it threw
  // ("component 'x' (type) threw ... from process()"), or nothing when it returned normally.
  // `call` names the method while it runs (for stuck-call and crash reports).
  template <class F>
  std::optional<std::string> guarded(const char* call, F&& f);
  // The component, for calls from other threads than the node's (interrupt, safe_state): a
  // restart may replace it meanwhile, so the pointer is read under a lock and the object kept
  // alive by the reference.
  std::shared_ptr<Component> current_component();
  // The stop path's calls, from the graph's stopping thread.
  void interrupt();
  SafeStateResult safe_state();
  // "component 'x' (type) failed: reason", or "... threw a non-exception ..." as it stands.
  std::string describe(const std::string& reason) const;

  Graph& graph;
  const ComponentConfig& config;
  const Spec& spec;
  Trigger trigger;
  bool is_sensor;
  bool timed;  // its type has stages: its calls are timed for the summary's time per stage
  bool dedicated;  // runs on a thread of its own (blocking components, or thread: dedicated)
  std::size_t executor_slot = 0;  // the executor's index for it (its dedicated thread), so enqueue does not search
  bool periodic() const { return trigger.policy == TriggerPolicy::Periodic; }

  std::shared_ptr<const Library> library;  // destroyed after the component
  std::vector<std::unique_ptr<InputState>> input_states;
  std::vector<std::unique_ptr<OutputState>> output_states;
  // The connections out of it that hold it back when full (lossless, not feedback), in one list:
  // ready() asks before every invocation.
  std::vector<const Buffer*> gating_outputs;
  std::vector<Input> inputs;    // sized once: components keep references
  std::vector<Output> outputs;
  std::shared_ptr<spdlog::logger> logger;
  std::unique_ptr<Context> context;
  std::shared_ptr<Component> component;  // swapped under component_mutex (restarts)
  PiMutex component_mutex;
  std::atomic<const char*> call{nullptr};  // the component method running now, if any
  // 0 not attempted, 1 attempting, 2 reached, 3 failed: a crash or forced exit knows what is left.
  std::atomic<int> safe_state_progress{0};

  std::atomic<int> state{Idle};
  std::atomic<bool> tick_pending{false};
  std::atomic<bool> finished{false};
  std::atomic<bool> in_process{false};
  bool finish_requested = false;  // set by Context::finish, acted on after process()
  std::atomic<bool> eos_delivered{false};
  bool constructing = false;
  struct EventRules {
    std::vector<const EventRule*> list;
    const std::string* producer = nullptr;  // "component.event", interned, in delivered headers
    std::atomic<std::uint64_t> next_seq{0};  // per source event, so a sink sees 0, 1, 2, ...
  };
  std::map<std::string, EventRules, std::less<>> rules;
  std::atomic<bool> ticking{false};  // periodic, and a tick will still come (see Graph::end_ticks)

  Counter invocations, errors, restarts, lost_to_restarts;
  Counter productive_calls;  // invocations that emitted something (Graph::progress)
  // Set by its outputs' sends, for productive_calls. Relaxed atomic: a plain store's cost, and no
  // data race if a component emits from a thread of its own.
  std::atomic<bool> emitted_in_call{false};
  std::atomic<std::int64_t> last_tick_ns{-1};  // for the stall warning: when the next tick is due
  PiMutex stage_mutex;  // components set their stage and report results from process()
  std::string stage;
  // Under stage_mutex: the time per stage (StageTime), and process()'s share of it so far.
  std::map<std::string, StageTime, std::less<>> stage_times;
  std::int64_t stage_clock_since_ns = 0;  // since when the current stage's time is not yet counted
  std::optional<std::chrono::steady_clock::time_point> busy_since;  // inside process(): the same for its busy time
  void count_stage_time();  // adds the current stage's time up to now; the caller holds stage_mutex
  std::map<std::string, std::string> results;  // Context::report
  void enter_stage(const std::string& next);  // takes stage_mutex

 private:
  bool outputs_have_room() const;
  bool inputs_closed() const;
  // False when an All trigger found no match; `taken` counts the samples taken, one per input at most.
  bool take_inputs(std::uint64_t& taken);
  // `lost`: the input samples the failed call had taken, counted if the component restarts.
  void fail(std::string_view reason, std::uint64_t lost = 0);
};

// Set around every component call (crash and exit reports). Initial-exec TLS, as in PiMutex: the
// default model for a shared library called __tls_get_addr twice a call.
extern thread_local const Node* t_active_node [[gnu::tls_model("initial-exec")]];
extern thread_local const char* t_active_call [[gnu::tls_model("initial-exec")]];

}  // namespace fba::detail
