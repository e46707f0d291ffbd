#include "graph.hpp"

#include <algorithm>
#include <sstream>

#include "fba/log.hpp"

namespace fba::detail {

// ---------------------------------------------------------------------------------------------
// Buffer

void Buffer::push(Packet&& p) {
  std::lock_guard lock(mutex);
  ++delivered;
  if (tap) {
    if (tap->size() >= tap_keep && !tap->empty()) tap->erase(tap->begin());
    if (tap_keep > 0) tap->push_back(std::move(p));
    return;
  }
  switch (policy) {
    case BufferPolicy::Latest:
      if (latest) ++dropped;  // superseded before anyone read it
      latest = std::move(p);
      size.store(1, std::memory_order_seq_cst);
      return;
    case BufferPolicy::DropOldest:
      if (queue.size() >= capacity) {
        queue.pop_front();
        ++dropped;
      }
      [[fallthrough]];
    case BufferPolicy::Lossless:
      queue.push_back(std::move(p));
      size.store(queue.size(), std::memory_order_seq_cst);
      return;
  }
}

bool Buffer::pop(Packet& out, bool& was_full) {
  std::lock_guard lock(mutex);
  was_full = false;
  if (policy == BufferPolicy::Latest) {
    if (!latest) return false;
    out = std::move(latest);
    latest = Packet();
    size.store(0, std::memory_order_seq_cst);
    return true;
  }
  if (queue.empty()) return false;
  was_full = gating && queue.size() >= capacity;
  out = std::move(queue.front());
  queue.pop_front();
  size.store(queue.size(), std::memory_order_seq_cst);
  return true;
}

std::int64_t Buffer::head_stamp() {
  std::lock_guard lock(mutex);
  if (policy == BufferPolicy::Latest) return latest.header().stamp_ns;
  return queue.front().header().stamp_ns;
}

// ---------------------------------------------------------------------------------------------
// Node

Node::Node(Graph& g, const ComponentConfig& c)
    : graph(g), config(c), spec(c.type->spec), trigger(c.trigger), is_sensor(spec.kind() == Kind::Sensor),
      dedicated(c.dedicated_thread || spec.is_blocking()) {
  library = c.type->library;
  for (const auto& ps : spec.inputs()) {
    auto st = std::make_unique<InputState>();
    st->spec = &ps;
    input_states.push_back(std::move(st));
  }
  for (const auto& ps : spec.outputs()) {
    auto st = std::make_unique<OutputState>();
    st->spec = &ps;
    st->producer = c.name + "." + ps.name;
    st->node = this;
    output_states.push_back(std::move(st));
  }
  inputs.resize(input_states.size());
  outputs.resize(output_states.size());
  for (std::size_t i = 0; i < inputs.size(); ++i) inputs[i].state_ = input_states[i].get();
  for (std::size_t i = 0; i < outputs.size(); ++i) outputs[i].state_ = output_states[i].get();
  logger = make_logger(c.name);
  context = std::make_unique<Context>(*this);
  if (!spec.stage_names().empty()) stage = spec.stage_names().front();
}

void Node::construct() {
  constructing = true;
  component = config.type->make(*context);
  constructing = false;
}

bool Node::outputs_have_room() const {
  for (const auto& out : output_states)
    for (const Buffer* b : out->consumers)
      if (b->full()) return false;
  return true;
}

bool Node::inputs_closed() const {
  bool any = false;
  for (const auto& in : input_states) {
    if (!in->buffer || !in->closes_node) continue;
    any = true;
    if (!in->closed()) return false;
  }
  return any;
}

bool Node::ready() const {
  if (finished.load(std::memory_order_relaxed) || !outputs_have_room()) return false;
  switch (trigger.policy) {
    case TriggerPolicy::Free:
      return true;
    case TriggerPolicy::Periodic:
      if (tick_pending.load(std::memory_order_seq_cst)) return true;
      break;
    case TriggerPolicy::Any:
      for (const auto& in : input_states)
        if (in->buffer && !in->buffer->empty()) return true;
      break;
    case TriggerPolicy::All: {
      bool all = false;
      for (const auto& in : input_states) {
        if (!in->buffer) continue;
        if (in->buffer->empty()) { all = false; break; }
        all = true;
      }
      if (all) return true;
      break;
    }
  }
  return !is_sensor && !eos_delivered && inputs_closed();
}

bool Node::take_inputs() {
  auto take = [this](std::size_t i) {
    Buffer* b = input_states[i]->buffer;
    bool was_full = false;
    Input& in = inputs[i];
    if (b && b->pop(in.current_, was_full)) {
      in.has_ = true;
      ++input_states[i]->received;
      if (was_full && b->producer) graph.notify(b->producer);
      return true;
    }
    return false;
  };
  for (auto& in : inputs) in.has_ = false;

  if (trigger.policy != TriggerPolicy::All) {
    bool any = false;
    for (std::size_t i = 0; i < inputs.size(); ++i) any |= take(i);
    return any;
  }
  // All: every connected input has a sample with the same stamp; older unmatched heads go.
  for (;;) {
    std::int64_t newest = INT64_MIN;
    for (const auto& in : input_states) {
      if (!in->buffer) continue;
      if (in->buffer->empty()) return false;
      newest = std::max(newest, in->buffer->head_stamp());
    }
    bool matched = true;
    for (std::size_t i = 0; i < input_states.size(); ++i) {
      Buffer* b = input_states[i]->buffer;
      if (!b || b->head_stamp() == newest) continue;
      matched = false;
      Packet dropped;
      bool was_full = false;
      b->pop(dropped, was_full);
      {
        std::lock_guard lock(b->mutex);
        ++b->dropped;
      }
      if (was_full && b->producer) graph.notify(b->producer);
    }
    if (matched) break;
  }
  for (std::size_t i = 0; i < inputs.size(); ++i) take(i);
  return true;
}

void Node::invoke() {
  const bool tick = periodic() && tick_pending.exchange(false, std::memory_order_acq_rel);
  bool has_input = false;
  for (const auto& in : input_states)
    if (in->buffer && !in->buffer->empty()) { has_input = true; break; }

  if (!is_sensor && !has_input && !tick && !eos_delivered && inputs_closed()) {
    eos_delivered = true;
    try {
      in_process.store(true, std::memory_order_relaxed);
      component->end_of_stream();
      in_process.store(false, std::memory_order_relaxed);
    } catch (const std::exception& e) {
      in_process.store(false, std::memory_order_relaxed);
      fail(e.what());
    }
    on_finish();
    return;
  }

  const bool took = take_inputs();
  switch (trigger.policy) {
    case TriggerPolicy::Any:
    case TriggerPolicy::All:
      if (!took) return;
      break;
    case TriggerPolicy::Periodic:
      if (!tick) return;
      break;
    case TriggerPolicy::Free:
      break;
  }
  ++invocations;
  try {
    in_process.store(true, std::memory_order_relaxed);
    component->process();
    in_process.store(false, std::memory_order_relaxed);
  } catch (const std::exception& e) {
    in_process.store(false, std::memory_order_relaxed);
    fail(e.what());
  } catch (...) {
    in_process.store(false, std::memory_order_relaxed);
    fail("unknown exception");
  }
  if (finish_requested && !finished.load()) on_finish();
}

void Node::fail(const std::string& reason) {
  ++errors;
  logger->error("failed in {}: {}", spec.type_name(), reason);
  emit_event("error", reason);
  if (graph.stopping()) return;  // a rule on the error event decided already
  if (config.on_error == ErrorPolicy::Restart && restarts < static_cast<std::uint64_t>(config.max_restarts)) {
    ++restarts;
    logger->warn("restarting ({} of at most {})", restarts, config.max_restarts);
    component.reset();
    try {
      construct();
      return;
    } catch (const std::exception& e) {
      graph.request_stop(Outcome::RuntimeError,
                         "component '" + config.name + "' could not be restarted: " + e.what());
      return;
    }
  }
  std::string why = "component '" + config.name + "' (" + spec.type_name() + ") failed: " + reason;
  if (config.on_error == ErrorPolicy::Restart) why += " (after " + std::to_string(restarts) + " restarts)";
  graph.request_stop(Outcome::RuntimeError, why);
}

void Node::emit_event(std::string_view name, std::string payload) {
  Event e{config.name, std::string(name), std::move(payload), graph.now_ns()};
  graph.record_event(e);
  auto it = rules.find(name);
  if (it == rules.end()) return;
  for (const EventRule* r : it->second) {
    switch (r->action) {
      case RuleAction::StopSuccess:
        graph.request_stop(Outcome::Success, "event " + config.name + "." + e.name, e);
        break;
      case RuleAction::StopFailure:
        graph.request_stop(Outcome::Failure, "event " + config.name + "." + e.name, e);
        break;
      case RuleAction::Deliver:
        graph.deliver(*r, e);
        break;
    }
  }
}

void Node::on_finish() {
  if (finished.exchange(true)) return;
  if (periodic()) graph.live_periodic.fetch_sub(1);
  emit_event("finished", {});
  for (const auto& out : output_states)
    for (Buffer* b : out->consumers) {
      b->producer_done.store(true, std::memory_order_seq_cst);
      if (b->consumer) graph.notify(b->consumer);
    }
}

// ---------------------------------------------------------------------------------------------
// Graph

Graph::Graph(const TaskConfig& cfg, RunOptions opts) : config(cfg), options(std::move(opts)) {
  task_dir = config.file.empty() ? std::filesystem::current_path() : config.file.parent_path();
  std::map<std::string, Node*> by_name;
  for (const auto& c : config.components) {
    nodes.push_back(std::make_unique<Node>(*this, c));
    by_name[c.name] = nodes.back().get();
  }
  auto input_of = [&](Node* n, const std::string& port) -> InputState* {
    for (auto& in : n->input_states)
      if (in->spec->name == port) return in.get();
    return nullptr;
  };
  for (const auto& c : config.connections) {
    Node* from = by_name.at(c.from);
    Node* to = by_name.at(c.to);
    auto b = std::make_unique<Buffer>();
    b->policy = c.policy;
    b->capacity = std::max<std::size_t>(1, c.capacity);
    // A back edge never holds its producer back: two full queues in a loop would otherwise
    // wait on each other forever. Its queue grows instead, by what the loop amplifies.
    b->gating = c.policy == BufferPolicy::Lossless && !c.feedback;
    b->feedback = c.feedback;
    b->producer = from;
    b->consumer = to;
    b->from = c.from + "." + c.from_port;
    b->to = c.to + "." + c.to_port;
    for (auto& out : from->output_states)
      if (out->spec->name == c.from_port) {
        out->consumers.push_back(b.get());
        out->type = c.type;
      }
    InputState* in = input_of(to, c.to_port);
    // A feedback input closes like any other: a node in a cycle never sees the end of its
    // stream while a sample may still come round, and the run ends when the graph is idle.
    in->buffer = b.get();
    buffers.push_back(std::move(b));
  }
  // Outputs nobody listens to still need their declared type for the emit check.
  for (auto& n : nodes)
    for (auto& out : n->output_states)
      if (!out->type) out->type = out->spec->type;
  for (const auto& r : config.rules) {
    Node* src = by_name.at(r.source);
    src->rules[r.event].push_back(&r);
    if (r.action != RuleAction::Deliver) continue;
    Node* dst = by_name.at(r.target);
    InputState* in = input_of(dst, r.target_port);
    if (!in->buffer) {  // one unbounded event queue per receiving input, shared by its rules
      auto b = std::make_unique<Buffer>();
      b->policy = BufferPolicy::Lossless;
      b->gating = false;
      b->consumer = dst;
      b->from = "events";
      b->to = r.target + "." + r.target_port;
      in->buffer = b.get();
      in->closes_node = false;
      buffers.push_back(std::move(b));
    }
  }
  const ExecutorKind kind = options.executor.value_or(config.executor);
  const int threads = options.threads > 0 ? options.threads : config.threads;
  executor_ = kind == ExecutorKind::Deterministic ? make_deterministic_executor(*this)
                                                  : make_threaded_executor(*this, threads);
  worker_threads = threads > 0 ? threads : static_cast<int>(std::max(2u, std::thread::hardware_concurrency()));
  timeout_s = options.timeout_s;
}

void Graph::construct() {
  for (auto& n : nodes) {
    try {
      n->construct();
    } catch (const ConfigError&) {
      throw;
    } catch (const PluginBug& e) {  // the component's code is wrong, not the task file
      throw ConfigError({Diagnostic{Location{n->config.type->origin, 0, 0}, e.what()}});
    } catch (const std::exception& e) {
      throw ConfigError({Diagnostic{n->config.where, "component '" + n->config.name + "' (" +
                                                         n->spec.type_name() + ") refused its configuration: " + e.what()}});
    }
  }
}

Graph::~Graph() {
  // Samples may hold memory whose deleter lives in a plugin: drop them before the plugins go.
  taps.clear();
  buffers.clear();
  for (auto& n : nodes) {
    for (auto& in : n->inputs) in = Input();
  }
  for (auto& n : nodes) n->component.reset();
}

Node& Graph::node(const std::string& name) {
  for (auto& n : nodes)
    if (n->config.name == name) return *n;
  throw std::logic_error("no component '" + name + "'");
}

void Graph::notify(Node* n) {
  int s = n->state.load(std::memory_order_seq_cst);  // after the caller's seq_cst store (see run_strand)
  for (;;) {
    if (s == Node::Idle) {
      if (n->state.compare_exchange_weak(s, Node::Queued, std::memory_order_acq_rel)) {
        active.fetch_add(1, std::memory_order_acq_rel);
        notifications.fetch_add(1, std::memory_order_acq_rel);
        executor_->enqueue(n);
        return;
      }
    } else if (s == Node::Running) {
      if (n->state.compare_exchange_weak(s, Node::RunningNotified, std::memory_order_acq_rel)) return;
    } else {
      return;
    }
  }
}

void Graph::run_strand(Node* n) {
  // A node's invocations never overlap: only the thread that moved it to Running runs it.
  //
  // Wake-ups follow Dekker's pattern: a producer stores to a buffer and then reads the
  // consumer's state; the consumer stores its state and then reads its buffers. Either may
  // otherwise see the other's old value (a store may pass a later load, even on x86), and a
  // sample would sit in an idle node's queue. So the buffer sizes, tick and end flags, and the
  // state written here are all sequentially consistent.
  constexpr int kBatch = 64;  // invocations before giving others a turn
  n->state.store(Node::Running, std::memory_order_seq_cst);
  for (;;) {
    int count = 0;
    while (count < kBatch && !stopping() && n->ready()) {
      n->invoke();
      ++count;
    }
    if (!stopping() && count == kBatch && n->ready()) {
      n->state.store(Node::Queued, std::memory_order_seq_cst);
      executor_->enqueue(n);
      return;
    }
    int expected = Node::Running;
    if (n->state.compare_exchange_strong(expected, Node::Idle, std::memory_order_seq_cst)) {
      if (active.fetch_sub(1, std::memory_order_acq_rel) == 1) executor_->poke();
      return;
    }
    n->state.store(Node::Running, std::memory_order_seq_cst);  // notified meanwhile: look again
  }
}

void Graph::check_idle() {
  // Timers (and a heal below) wake nodes from outside any running node, so "nothing runs" can
  // stop being true while this looks: every conclusion is re-checked against the count of
  // notifications taken at the start, and dropped if anything woke meanwhile.
  const auto seen = notifications.load(std::memory_order_acquire);
  if (stopping() || active.load(std::memory_order_acquire) != 0) return;
  auto quiet = [&] { return notifications.load(std::memory_order_acquire) == seen && active.load(std::memory_order_acquire) == 0; };
  bool has_sensor = false, sensors_done = true;
  for (auto& n : nodes)
    if (n->is_sensor) {
      has_sensor = true;
      sensors_done &= n->finished.load();
    }
  if (has_sensor && sensors_done) {
    request_stop(Outcome::Success, "every sensor finished and all data was processed");
    return;
  }
  if (live_periodic.load() > 0) return;  // a timer will bring more work
  // A node that is ready but idle while nothing else runs would be a lost wake-up, which is a
  // bug: say so loudly and run it rather than end the task.
  std::vector<Node*> ready_idle;
  for (auto& n : nodes)
    if (n->state.load() == Node::Idle && n->ready()) ready_idle.push_back(n.get());
  if (!quiet()) return;
  for (Node* n : ready_idle) {
    n->logger->warn("was ready but not scheduled (lost wake-up); scheduling it now");
    record_event(Event{n->config.name, "lost_wakeup", "a runtime bug: please report it", now_ns()});
    notify(n);
  }
  if (!ready_idle.empty()) return;
  std::ostringstream why;
  why << "stalled: no component can run and the task has not ended";
  for (auto& n : nodes) {
    if (n->finished.load()) continue;
    std::vector<std::string> waits;
    for (auto& out : n->output_states)
      for (Buffer* b : out->consumers)
        if (b->full()) waits.push_back("held back by the full lossless queue " + b->from + " -> " + b->to);
    if (waits.empty())
      for (auto& in : n->input_states)
        if (in->buffer && in->buffer->empty() && !in->closed()) waits.push_back("waiting on input '" + in->spec->name + "'");
    if (!waits.empty()) why << "; " << n->config.name << ": " << waits.front();
  }
  if (quiet()) request_stop(Outcome::RuntimeError, why.str());
}

void Graph::request_stop(Outcome outcome, const std::string& reason, std::optional<Event> event) {
  {
    std::lock_guard lock(result_mutex_);
    if (stopping_.load()) return;
    result_.outcome = outcome;
    result_.reason = reason;
    result_.final_event = std::move(event);
    stopping_.store(true, std::memory_order_release);
  }
  if (executor_) executor_->wake_all();
}

void Graph::record_event(const Event& e) {
  std::lock_guard lock(result_mutex_);
  if (events_.size() < 10000) events_.push_back(e);
}

void Graph::deliver(const EventRule& rule, const Event& e) {
  Node& dst = node(rule.target);
  for (auto& in : dst.input_states)
    if (in->spec->name == rule.target_port) {
      in->buffer->push(Packet::make<Event>(std::make_shared<const Event>(e), Header{0, e.stamp_ns, nullptr}));
      notify(&dst);
      return;
    }
}

std::vector<Packet>& Graph::tap(const std::string& port, std::size_t keep) {
  const auto dot = port.rfind('.');
  if (dot == std::string::npos) throw std::invalid_argument("tap needs 'component.output', got '" + port + "'");
  Node& n = node(port.substr(0, dot));
  for (auto& out : n.output_states)
    if (out->spec->name == port.substr(dot + 1)) {
      taps.emplace_back();
      auto b = std::make_unique<Buffer>();
      b->tap = &taps.back();
      b->tap_keep = keep;
      b->from = port;
      b->to = "tap";
      out->consumers.push_back(b.get());
      buffers.push_back(std::move(b));
      return taps.back();
    }
  throw std::invalid_argument("component '" + n.config.name + "' has no output '" + port.substr(dot + 1) + "'");
}

ThreadPool& Graph::thread_pool() {
  std::lock_guard lock(pool_mutex_);
  if (!pool_) pool_ = std::make_unique<ThreadPool>(worker_threads);
  return *pool_;
}

RunResult Graph::run() {
  if (ran_) throw std::logic_error("a task runs once");
  ran_ = true;
  started = std::chrono::steady_clock::now();
  for (auto& n : nodes)
    if (n->periodic()) live_periodic.fetch_add(1);
  for (auto& n : nodes) notify(n.get());
  executor_->run();  // returns with every thread joined

  for (auto& n : nodes) {
    if (n->spec.kind() != Kind::Actuator || !n->component) continue;
    try {
      n->component->safe_state();
      n->logger->info("safe state reached");
    } catch (const std::exception& e) {
      n->logger->error("could not reach a safe state: {}", e.what());
      std::lock_guard lock(result_mutex_);
      if (result_.outcome == Outcome::Success) {
        result_.outcome = Outcome::RuntimeError;
        result_.reason = "component '" + n->config.name + "' could not reach a safe state: " + e.what();
      }
    }
  }

  std::lock_guard lock(result_mutex_);
  RunResult r = result_;
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  r.events = events_;
  for (auto& n : nodes) {
    ComponentStats s;
    s.name = n->config.name;
    s.type = n->spec.type_name();
    s.kind = n->spec.kind();
    s.invocations = n->invocations;
    for (auto& in : n->input_states) s.samples_in += in->received;
    for (auto& out : n->output_states) s.samples_out += out->next_seq;
    s.errors = n->errors;
    s.restarts = n->restarts;
    {
      std::lock_guard stage_lock(n->stage_mutex);
      s.stage = n->stage;
    }
    r.components.push_back(std::move(s));
  }
  for (auto& b : buffers) {
    if (b->tap || !b->producer) continue;
    std::lock_guard block(b->mutex);
    r.connections.push_back(ConnectionStats{b->from, b->to, b->policy, b->delivered, b->dropped});
  }
  return r;
}

}  // namespace fba::detail

namespace fba {

Task::Task(const TaskConfig& config, RunOptions options)
    : graph_(std::make_unique<detail::Graph>(config, std::move(options))) {
  graph_->construct();
}
Task::~Task() = default;
const std::vector<Packet>& Task::tap(const std::string& port, std::size_t keep) { return graph_->tap(port, keep); }
RunResult Task::run() { return graph_->run(); }
void Task::request_stop(Outcome outcome, const std::string& reason) { graph_->request_stop(outcome, reason); }

}  // namespace fba
