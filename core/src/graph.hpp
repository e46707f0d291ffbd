// Runtime internals: buffers between ports, nodes (a component and its ports), the graph and
// the executors that run it. Not part of the public API.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <stop_token>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "fba/component.hpp"
#include "fba/task.hpp"
#include "fba/task_config.hpp"
#include "fba/thread_pool.hpp"
#include "pi_mutex.hpp"

namespace fba::detail {

class Node;
class Graph;

// Limits the runtime enforces, documented in docs/task-files.md.
constexpr std::size_t kMaxEventPayload = 64 * 1024;    // bytes; longer payloads are truncated
// Durations are int64 nanoseconds on the executor's clock; a period or a time-out longer than
// this (about 285 years) means "never within this run". Kept below INT64_MAX so that adding it
// to a steady clock reading cannot overflow.
constexpr double kMaxDurationS = 9e9;
constexpr std::int64_t kNeverNs = INT64_MAX;
// Seconds to nanoseconds, saturating at kNeverNs (NaN and infinity included).
std::int64_t duration_ns(double seconds);
// a + b for non-negative b, saturating at kNeverNs.
inline std::int64_t add_ns(std::int64_t a, std::int64_t b) { return a > kNeverNs - b ? kNeverNs : a + b; }

// A count written by one thread (a node's strand) and read by others while the task runs (the
// live graph dump): a relaxed atomic, so the reads are not data races, at the cost of a plain
// increment.
class Counter {
 public:
  std::uint64_t get() const { return v_.load(std::memory_order_relaxed); }
  operator std::uint64_t() const { return get(); }
  std::uint64_t operator++(int) {  // post-increment: the value before
    const std::uint64_t old = get();
    v_.store(old + 1, std::memory_order_relaxed);
    return old;
  }
  Counter& operator++() { (*this)++; return *this; }
  Counter& operator+=(std::uint64_t d) { v_.store(get() + d, std::memory_order_relaxed); return *this; }
  void raise_to(std::uint64_t v) {  // a running maximum
    if (v > get()) v_.store(v, std::memory_order_relaxed);
  }

 private:
  std::atomic<std::uint64_t> v_{0};
};

// A name that lives as long as the process (headers point to it: a packet may outlive its task).
const std::string* intern_name(std::string_view name);

// One connection's storage, in front of one input.
//
// The lock is a priority-inheriting mutex, not a spinlock or a plain mutex: under real-time
// priorities a spinning waiter can keep the preempted holder from ever running, and a plain mutex
// lets a medium-priority thread delay a high-priority waiter without bound. Packets leaving the buffer (displaced, dropped, or an
// input's previous sample) are destroyed after it is released: one may be a whole frame.
struct Buffer {
  BufferPolicy policy = BufferPolicy::Lossless;
  std::size_t capacity = 16;
  std::size_t max_bytes = 0;  // payload bytes queued at most; 0 for no byte budget
  bool gating = false;  // a full buffer holds its producer back (lossless connections)
  bool feedback = false;
  // Every push and pop on one thread (the deterministic executor's data connections): no lock,
  // since the snapshots other threads take read only the atomic size and counts.
  bool one_thread = false;
  Node* producer = nullptr;  // null for event deliveries
  Node* consumer = nullptr;  // null for taps
  std::string from, to;      // "component.port", for messages and statistics

  PiMutex mutex;
  std::deque<Packet> queue;  // Lossless and DropOldest
  Packet latest;             // Latest
  std::atomic<std::size_t> size{0};   // readable without the lock, for scheduling decisions
  std::size_t queued_bytes = 0;        // payload bytes queued, under the lock
  std::atomic<std::size_t> bytes{0};  // queued_bytes, published for full() when max_bytes > 0
  std::atomic<bool> producer_done{false};
  // Written under the lock, read by snapshots without it. Every sample pushed is consumed, dropped
  // by the policy, or still queued: pushed = consumed + dropped + queued().
  Counter pushed, consumed, dropped;
  Counter peak, peak_bytes;  // the most samples and bytes queued at once
  std::size_t tap_keep = SIZE_MAX;
  std::vector<Packet>* tap = nullptr;  // set for taps: packets are appended, at most tap_keep kept

  void push(Packet&& p);
  // Pops the head; `was_full` tells the caller to wake a producer held back by this buffer.
  bool pop(Packet& out, bool& was_full);
  // Drops the head, counted as dropped (an All trigger's unmatched sample).
  bool drop_head(bool& was_full);
  bool full() const {
    return gating && (size.load(std::memory_order_seq_cst) >= capacity ||
                      (max_bytes > 0 && bytes.load(std::memory_order_seq_cst) >= max_bytes));
  }
  bool empty() const { return size.load(std::memory_order_seq_cst) == 0; }
  // Peeks at the head's stamp (All trigger matching); requires non-empty.
  std::int64_t head_stamp();
  // Samples still queued (at the stop: left unseen). Takes the lock.
  std::size_t queued();

 private:
  bool take_head(Packet& out, bool& was_full);  // under the lock
  void publish_size();                          // under the lock
};

// A buffer's lock, taken unless one thread does every push and pop (Buffer::one_thread).
class BufferLock {
 public:
  explicit BufferLock(Buffer& b) : b_(b.one_thread ? nullptr : &b) {
    if (b_) b_->mutex.lock();
  }
  ~BufferLock() {
    if (b_) b_->mutex.unlock();
  }
  BufferLock(const BufferLock&) = delete;
  BufferLock& operator=(const BufferLock&) = delete;

 private:
  Buffer* b_;
};

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
  // ("component 'x' (type) threw ... from process()"), or empty when it returned normally.
  // `call` names the method while it runs (for stuck-call and crash reports).
  template <class F>
  std::string guarded(const char* call, F&& f);
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
  bool dedicated;  // runs on a thread of its own (blocking components, or thread: dedicated)
  std::size_t executor_slot = 0;  // the executor's index for it (its dedicated thread), so enqueue does not search
  bool periodic() const { return trigger.policy == TriggerPolicy::Periodic; }

  std::shared_ptr<const Library> library;  // destroyed after the component
  std::vector<std::unique_ptr<InputState>> input_states;
  std::vector<std::unique_ptr<OutputState>> output_states;
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
  bool take_inputs();  // false when an All trigger found no match
  std::uint64_t samples_emitted() const;
  // `lost`: the input samples the failed call had taken, counted if the component restarts.
  void fail(std::string_view reason, std::uint64_t lost = 0);
};

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

// Set around every component call (crash and exit reports). Initial-exec TLS, as in PiMutex: the
// default model for a shared library called __tls_get_addr twice a call.
extern thread_local const Node* t_active_node [[gnu::tls_model("initial-exec")]];
extern thread_local const char* t_active_call [[gnu::tls_model("initial-exec")]];

std::unique_ptr<Executor> make_threaded_executor(Graph& g, int threads);
std::unique_ptr<Executor> make_deterministic_executor(Graph& g);

}  // namespace fba::detail
