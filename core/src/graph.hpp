// Runtime internals: buffers between ports, nodes (a component and its ports), the graph and
// the executors that run it. Not part of the public API.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "fba/component.hpp"
#include "fba/task.hpp"
#include "fba/task_config.hpp"
#include "fba/thread_pool.hpp"

namespace fba::detail {

class Node;
class Graph;

// A lock for critical sections of a few instructions (a queue push or pop), where a mutex's
// sleep and wake would cost more than the work; it yields if the holder was preempted.
class SpinLock {
 public:
  void lock() {
    for (int spins = 0; flag_.exchange(true, std::memory_order_acquire); ++spins) {
      while (flag_.load(std::memory_order_relaxed)) {
        if (++spins > 64) std::this_thread::yield();
      }
    }
  }
  void unlock() { flag_.store(false, std::memory_order_release); }

 private:
  std::atomic<bool> flag_{false};
};

// One connection's storage, in front of one input.
struct Buffer {
  BufferPolicy policy = BufferPolicy::Lossless;
  std::size_t capacity = 16;
  bool gating = false;  // a full buffer holds its producer back (lossless connections)
  bool feedback = false;
  Node* producer = nullptr;  // null for event deliveries
  Node* consumer = nullptr;  // null for taps
  std::string from, to;      // "component.port", for messages and statistics

  SpinLock mutex;
  std::deque<Packet> queue;  // Lossless and DropOldest
  Packet latest;             // Latest
  std::atomic<std::size_t> size{0};  // readable without the lock, for scheduling decisions
  std::atomic<bool> producer_done{false};
  std::uint64_t delivered = 0, dropped = 0;
  std::size_t tap_keep = SIZE_MAX;
  std::vector<Packet>* tap = nullptr;  // set for taps: packets are appended, at most tap_keep kept

  void push(Packet&& p);
  // Pops the head; `was_full` tells the caller to wake a producer held back by this buffer.
  bool pop(Packet& out, bool& was_full);
  bool full() const { return gating && size.load(std::memory_order_seq_cst) >= capacity; }
  bool empty() const { return size.load(std::memory_order_seq_cst) == 0; }
  // Peeks at the head's stamp (All trigger matching); requires non-empty.
  std::int64_t head_stamp();
};

struct InputState {
  const PortSpec* spec = nullptr;
  Buffer* buffer = nullptr;
  bool closes_node = true;  // false for event inputs: events are not a stream that ends
  std::uint64_t received = 0;
  bool closed() const {
    return buffer == nullptr || (buffer->producer_done.load(std::memory_order_seq_cst) && buffer->empty());
  }
};

struct OutputState {
  const PortSpec* spec = nullptr;
  const TypeInfo* type = nullptr;  // resolved (outputs typed like an input get that type)
  std::vector<Buffer*> consumers;
  std::string producer;  // "component.output", pointed to by every header
  std::uint64_t next_seq = 0;
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
  void emit_event(std::string_view name, std::string payload);
  void on_finish();  // marks finished and tells the consumers

  Graph& graph;
  const ComponentConfig& config;
  const Spec& spec;
  Trigger trigger;
  bool is_sensor;
  bool dedicated;  // runs on a thread of its own (blocking components, or thread: dedicated)
  bool periodic() const { return trigger.policy == TriggerPolicy::Periodic; }

  std::shared_ptr<const Library> library;  // destroyed after the component
  std::vector<std::unique_ptr<InputState>> input_states;
  std::vector<std::unique_ptr<OutputState>> output_states;
  std::vector<Input> inputs;    // sized once: components keep references
  std::vector<Output> outputs;
  std::shared_ptr<spdlog::logger> logger;
  std::unique_ptr<Context> context;
  std::unique_ptr<Component> component;

  std::atomic<int> state{Idle};
  std::atomic<bool> tick_pending{false};
  std::atomic<bool> finished{false};
  std::atomic<bool> in_process{false};
  bool finish_requested = false;  // set by Context::finish, acted on after process()
  std::atomic<bool> eos_delivered{false};
  bool constructing = false;
  std::map<std::string, std::vector<const EventRule*>, std::less<>> rules;

  std::uint64_t invocations = 0, errors = 0, restarts = 0;
  std::mutex stage_mutex;
  std::string stage;

 private:
  bool outputs_have_room() const;
  bool inputs_closed() const;
  bool take_inputs();  // false when an All trigger found no match
  void fail(const std::string& reason);
};

class Executor {
 public:
  virtual ~Executor() = default;
  virtual void enqueue(Node* n) = 0;
  virtual std::int64_t now_ns() const = 0;
  // Runs until the graph stops; returns with every thread joined.
  virtual void run() = 0;
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
  void request_stop(Outcome outcome, const std::string& reason, std::optional<Event> event = {});
  bool stopping() const { return stopping_.load(std::memory_order_acquire); }
  std::int64_t now_ns() const { return executor_->now_ns(); }
  void record_event(const Event& e);
  void deliver(const EventRule& rule, const Event& e);
  std::vector<Packet>& tap(const std::string& port, std::size_t keep = SIZE_MAX);
  // Created on first use, with as many threads as the executor has workers.
  ThreadPool& thread_pool();
  RunResult run();
  std::vector<Event> events() {
    std::lock_guard lock(result_mutex_);
    return events_;
  }
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
  std::chrono::steady_clock::time_point started;
  double timeout_s = 0;
  int worker_threads = 2;

 private:
  std::mutex pool_mutex_;
  std::unique_ptr<ThreadPool> pool_;
  Node& node(const std::string& name);
  std::atomic<bool> stopping_{false};
  std::mutex result_mutex_;
  RunResult result_;
  std::vector<Event> events_;
  bool ran_ = false;
};

std::unique_ptr<Executor> make_threaded_executor(Graph& g, int threads);
std::unique_ptr<Executor> make_deterministic_executor(Graph& g);

}  // namespace fba::detail
