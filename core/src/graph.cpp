#include "graph.hpp"

#include <signal.h>

#include <algorithm>
#include <sstream>
#include <system_error>
#include <unordered_set>

#include "fba/message_text.hpp"
#include "fba/log.hpp"

namespace fba::detail {

// ---------------------------------------------------------------------------------------------
// Limits and names

std::int64_t duration_ns(double seconds) {
  if (!(seconds < kMaxDurationS)) return kNeverNs;  // NaN too
  return std::max<std::int64_t>(0, static_cast<std::int64_t>(seconds * 1e9));
}

const std::string* intern_name(std::string_view name) {
  // Never freed, and never destroyed at exit: a packet held in a static may still point here.
  static auto* mutex = new std::mutex;
  static auto* names = new std::unordered_set<std::string>;
  std::lock_guard lock(*mutex);
  return &*names->emplace(name).first;
}

namespace {

// Text for an event payload: at most kMaxEventPayload bytes, the cut marked and not inside a
// UTF-8 character.
std::string bounded_payload(std::string_view text) {
  if (text.size() <= kMaxEventPayload) return std::string(text);
  const std::string marker = " [truncated: " + std::to_string(text.size()) + " bytes in all]";
  std::size_t cut = kMaxEventPayload - marker.size();
  while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) --cut;
  return std::string(text.substr(0, cut)) + marker;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Buffer

void Buffer::publish_size() {
  const std::size_t n = policy == BufferPolicy::Latest ? (latest ? 1 : 0) : queue.size();
  // Sequentially consistent for the wake-up protocol (Graph::run_strand) between threads; one
  // thread running every node has no such race, and the fence was a fifth of its hop.
  // (Two stores, not one with a computed order: GCC makes any order not known at compile time
  // sequentially consistent.)
  if (one_thread)
    size.store(n, std::memory_order_relaxed);
  else
    size.store(n, std::memory_order_seq_cst);
  if (max_bytes > 0) bytes.store(queued_bytes, std::memory_order_seq_cst);  // read by full() only
  peak.raise_to(n);
  peak_bytes.raise_to(queued_bytes);
}

void Buffer::push(Packet&& p) {
  std::vector<Packet> displaced;  // declared before the lock: destroyed after it is released
  BufferLock lock(*this);
  ++pushed;
  if (tap) {
    if (tap->size() >= tap_keep && !tap->empty()) {
      displaced.push_back(std::move(tap->front()));
      tap->erase(tap->begin());
    }
    if (tap_keep > 0) tap->push_back(std::move(p));
    return;
  }
  const std::size_t b = p.bytes();
  switch (policy) {
    case BufferPolicy::Latest:
      if (latest) {  // superseded before anyone read it
        ++dropped;
        displaced.push_back(std::move(latest));
      }
      latest = std::move(p);
      queued_bytes = b;
      break;
    case BufferPolicy::DropOldest:
      while (!queue.empty() && (queue.size() >= capacity || (max_bytes > 0 && queued_bytes + b > max_bytes))) {
        queued_bytes -= queue.front().bytes();
        displaced.push_back(std::move(queue.front()));
        queue.pop_front();
        ++dropped;
      }
      [[fallthrough]];
    case BufferPolicy::Lossless:
      queue.push_back(std::move(p));
      queued_bytes += b;
      break;
  }
  publish_size();
}

bool Buffer::take_head(Packet& out, bool& was_full) {
  was_full = false;
  if (policy == BufferPolicy::Latest) {
    if (!latest) return false;
    out = std::move(latest);
    latest = Packet();
  } else {
    if (queue.empty()) return false;
    was_full = full();
    out = std::move(queue.front());
    queue.pop_front();
  }
  queued_bytes -= out.bytes();
  publish_size();
  return true;
}

bool Buffer::pop(Packet& out, bool& was_full) {
  Packet taken;
  {
    BufferLock lock(*this);
    if (!take_head(taken, was_full)) return false;
    ++consumed;
  }
  out = std::move(taken);  // frees the input's previous sample, outside the lock
  return true;
}

bool Buffer::drop_head(bool& was_full) {
  Packet taken;  // declared before the lock: destroyed after it is released
  BufferLock lock(*this);
  if (!take_head(taken, was_full)) return false;
  ++dropped;
  return true;
}

std::int64_t Buffer::head_stamp() {
  BufferLock lock(*this);
  if (policy == BufferPolicy::Latest) return latest.header().stamp_ns;
  return queue.front().header().stamp_ns;
}

std::size_t Buffer::queued() {
  if (tap) return 0;
  if (one_thread) return size.load(std::memory_order_relaxed);  // another thread may be asking
  std::lock_guard lock(mutex);
  return policy == BufferPolicy::Latest ? (latest ? 1 : 0) : queue.size();
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
    auto st = std::make_unique<OutputState>(*intern_name(c.name + "." + ps.name));
    st->spec = &ps;
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

// The component call running on this thread, for crash and exit reports (see active_call).
thread_local const Node* t_active_node [[gnu::tls_model("initial-exec")]] = nullptr;
thread_local const char* t_active_call [[gnu::tls_model("initial-exec")]] = nullptr;

namespace {

// Marks this thread as running one of a node's calls, for as long as it lives.
class ActiveScope {
 public:
  ActiveScope(const Node* n, const char* call) : node_(t_active_node), call_(t_active_call) {
    t_active_node = n;
    t_active_call = call;
  }
  ~ActiveScope() {
    t_active_node = node_;
    t_active_call = call_;
  }
  ActiveScope(const ActiveScope&) = delete;
  ActiveScope& operator=(const ActiveScope&) = delete;

 private:
  const Node* node_;
  const char* call_;
};

// Runs f, catching everything; returns what it threw, worded for "component 'x' (type) ...".
// The exception's text may echo a parameter from the task file: its control bytes are escaped.
template <class F>
std::string catch_all(const char* call, F&& f) {
  try {
    f();
    return {};
  } catch (const std::exception& e) {
    const std::string what = escape_controls(e.what());
    if (std::string_view(call) == "process()") return what;  // the common case keeps its short form
    return what + " (thrown from " + call + ")";
  } catch (...) {
    return std::string("threw a non-exception (not derived from std::exception) from ") + call;
  }
}

}  // namespace

std::string Node::describe(const std::string& reason) const {
  const std::string who = "component '" + config.name + "' (" + spec.type_name() + ") ";
  return who + (reason.rfind("threw ", 0) == 0 ? reason : "failed: " + reason);
}

template <class F>
std::string Node::guarded(const char* what, F&& f) {
  ActiveScope active(this, what);
  // Release, not sequentially consistent (an exchange: a third of a light hop): the stop reads it
  // to name calls still running and to interrupt those in a call, and a call it misses as it starts
  // is not waiting on anything yet; blocking components are interrupted in any case.
  call.store(what, std::memory_order_release);
  std::string error = catch_all(what, std::forward<F>(f));
  call.store(nullptr, std::memory_order_release);
  return error;
}

void Node::construct() {
  ActiveScope active(this, "its constructor");
  constructing = true;
  std::unique_ptr<Component> made;
  try {
    made = config.type->make(*context);
  } catch (...) {
    constructing = false;
    throw;
  }
  constructing = false;
  std::lock_guard lock(component_mutex);
  component = std::move(made);
}

std::shared_ptr<Component> Node::current_component() {
  std::lock_guard lock(component_mutex);
  return component;
}

void Node::interrupt() {
  auto c = current_component();
  if (!c) return;
  ActiveScope active(this, "interrupt()");
  const std::string error = catch_all("interrupt()", [&] { c->interrupt(); });
  if (error.empty()) return;
  logger->error("{}", describe(error));
  graph.record_event(Event{config.name, "error", error, graph.now_ns()});
}

namespace {
// An actuator whose safe_state() was still running when the stop grace ran out.
SafeStateResult safe_state_not_returned(const std::string& component) {
  return {component, "did not return", "safe_state() did not return within the stop grace"};
}
}  // namespace

SafeStateResult Node::safe_state() {
  SafeStateResult r{config.name, "not constructed", {}};
  auto c = current_component();
  int expected = 0;
  if (!c || !safe_state_progress.compare_exchange_strong(expected, 1)) {
    if (c) r.status = "already attempted";
    return r;
  }
  ActiveScope active(this, "safe_state()");
  r.message = catch_all("safe_state()", [&] { c->safe_state(); });
  r.status = r.message.empty() ? "reached" : "failed";
  safe_state_progress.store(r.message.empty() ? 2 : 3);
  if (r.message.empty())
    logger->info("safe state reached");
  else
    logger->error("could not reach a safe state: {}", describe(r.message));
  return r;
}

std::uint64_t Node::samples_emitted() const {
  std::uint64_t n = 0;
  for (const auto& out : output_states) n += out->next_seq;
  return n;
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
      bool was_full = false;
      b->drop_head(was_full);
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
    const std::string error = guarded("end_of_stream()", [&] { component->end_of_stream(); });
    if (!error.empty()) fail(error);
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
      last_tick_ns.store(graph.now_ns(), std::memory_order_relaxed);
      break;
    case TriggerPolicy::Free:
      break;
  }
  ++invocations;
  std::uint64_t taken = 0;
  for (const auto& in : inputs) taken += in.has_ ? 1 : 0;
  const std::uint64_t emitted = samples_emitted();
  // `component` is only replaced on this thread (a restart), so it is read here without the lock.
  // Only a type with stages has its calls timed (for the summary's time per stage): the two clock
  // reads and locks would be a tenth of a light component's hop.
  const bool timed = !spec.stage_names().empty();
  if (timed) {
    std::lock_guard lock(stage_mutex);
    busy_since = std::chrono::steady_clock::now();
  }
  const std::string error = guarded("process()", [&] { component->process(); });
  if (timed) {
    std::lock_guard lock(stage_mutex);
    count_stage_time();
    busy_since.reset();
  }
  if (!error.empty())
    fail(error, taken);
  else if (samples_emitted() != emitted)
    ++productive_calls;
  if (finish_requested && !finished.load()) on_finish();
}

void Node::count_stage_time() {
  const auto now = std::chrono::steady_clock::now();
  const std::int64_t clock = graph.now_ns();
  auto& current = stage_times[stage];
  current.clock_s += static_cast<double>(clock - stage_clock_since_ns) * 1e-9;
  stage_clock_since_ns = clock;
  if (busy_since) {
    current.busy_s += std::chrono::duration<double>(now - *busy_since).count();
    busy_since = now;
  }
}

void Node::enter_stage(const std::string& next) {
  std::lock_guard lock(stage_mutex);
  count_stage_time();
  stage = next;
  ++stage_times[next].entered;
}

void Node::fail(std::string_view what, std::uint64_t lost) {
  // An exception's message becomes an event payload and the run's reason: bounded like one.
  if (what.size() > kMaxEventPayload)
    logger->warn("its error message has {} bytes; only the first {} are kept (the limit for an event payload)",
                 what.size(), kMaxEventPayload);
  const std::string reason = bounded_payload(what);
  ++errors;
  // A call the stop cut short (a driver whose safe state took its line) is the stop's doing, not
  // a failure to alarm anyone with: said, at info.
  if (graph.stopping())
    logger->info("{} (during the stop)", describe(reason));
  else
    logger->error("{}", describe(reason));
  emit_event("error", reason);
  if (graph.stopping()) return;  // the stop, or a rule on the error event, decided already
  if (config.on_error == ErrorPolicy::Restart && restarts < static_cast<std::uint64_t>(config.max_restarts)) {
    ++restarts;
    lost_to_restarts += lost;
    logger->warn("restarting ({} of at most {}); {} input sample(s) lost with the failed call", restarts,
                 config.max_restarts, lost);
    std::shared_ptr<Component> old;
    {
      std::lock_guard lock(component_mutex);
      old = std::move(component);
    }
    old.reset();  // the old instance releases its devices before the new one opens them
    const std::string error = catch_all("its constructor", [&] { construct(); });
    if (!error.empty())
      graph.request_stop(Outcome::RuntimeError,
                         "component '" + config.name + "' (" + spec.type_name() + ") could not be restarted: " + error);
    return;
  }
  std::string why = describe(reason);
  if (config.on_error == ErrorPolicy::Restart) why += " (after " + std::to_string(restarts) + " restarts)";
  graph.request_stop(Outcome::RuntimeError, why);
}

void Node::emit_event(std::string_view name, std::string payload) {
  if (payload.size() > kMaxEventPayload) {
    logger->warn("event '{}' carries {} bytes; only the first {} are kept (the limit for an event payload)", name,
                 payload.size(), kMaxEventPayload);
    payload = bounded_payload(payload);
  }
  auto e = std::make_shared<const Event>(Event{config.name, std::string(name), std::move(payload), graph.now_ns()});
  graph.record_event(e);
  auto it = rules.find(name);
  if (it == rules.end()) return;
  EventRules& event_rules = it->second;
  const Header header{event_rules.next_seq.fetch_add(1, std::memory_order_relaxed), e->stamp_ns, event_rules.producer};
  for (const EventRule* r : event_rules.list) {
    switch (r->action) {
      case RuleAction::StopSuccess:
        graph.request_stop(Outcome::Success, "event " + config.name + "." + e->name, e);
        break;
      case RuleAction::StopFailure:
        graph.request_stop(Outcome::Failure, "event " + config.name + "." + e->name, e);
        break;
      case RuleAction::Deliver:
        graph.deliver(*r, e, header);
        break;
    }
  }
}

void Node::on_finish() {
  if (finished.exchange(true)) return;
  graph.end_ticks(this);
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
  // While constructing, a caller's stop reaches the constructors through the stop token and
  // construct() ends the construction; after it, the stop is a stop of the run.
  external_stop_.emplace(options.stop, std::function<void()>([this] {
    stop_source_.request_stop();
    if (constructed_.load()) request_stop(Outcome::Interrupted, "stop requested");
  }));
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
    b->max_bytes = c.max_bytes;
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
  // Outputs nobody listens to still need their type for the emit check: as the loader resolved it.
  for (auto& n : nodes)
    for (auto& out : n->output_states)
      if (!out->type) {
        const auto t = n->config.output_types.find(out->spec->name);
        out->type = t != n->config.output_types.end() ? t->second : out->spec->type;
      }
  for (const auto& r : config.rules) {
    Node* src = by_name.at(r.source);
    auto& event_rules = src->rules[r.event];
    event_rules.list.push_back(&r);
    event_rules.producer = intern_name(r.source + "." + r.event);
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
  const int threads = options.threads != 0 ? options.threads : config.threads;
  // Refused before any thread starts: past these the system runs out of threads, and a run
  // that fails half-started is worse than one that never starts.
  const Location task_location{config.file.empty() ? std::string("the task") : config.file.string()};
  if (threads < 0 || threads > kMaxThreads)
    throw ConfigError({Diagnostic{task_location, "threads must be in [0, " + std::to_string(kMaxThreads) +
                                                    "] (0: one per core); found " + std::to_string(threads)}});
  if (kind == ExecutorKind::Threaded) {
    std::size_t dedicated = 0;
    for (auto& n : nodes) dedicated += n->dedicated ? 1 : 0;
    if (dedicated > kMaxDedicatedThreads)
      throw ConfigError({Diagnostic{task_location, std::to_string(dedicated) +
                                                      " components need a thread of their own (thread: dedicated, or a "
                                                      "blocking type); at most " +
                                                      std::to_string(kMaxDedicatedThreads) + " may"}});
  }
  // One thread pushes and pops every buffer under the deterministic executor: no wake-up races.
  // Event queues are left out: a rule delivers the events of a safe state, which may run on a
  // thread of its own beside the executor's.
  for (auto& b : buffers) b->one_thread = kind == ExecutorKind::Deterministic && b->producer != nullptr;
  executor_ = kind == ExecutorKind::Deterministic ? make_deterministic_executor(*this)
                                                  : make_threaded_executor(*this, threads);
  worker_threads = threads > 0 ? threads : static_cast<int>(std::max(2u, std::thread::hardware_concurrency()));
  timeout_s = options.timeout_s;
}

void Graph::construct() {
  constructing_since = std::chrono::steady_clock::now();
  for (auto& n : nodes) {
    if (stop_source_.stop_requested()) break;
    std::string error;
    bool device = false;
    try {
      n->construct();
    } catch (const ConfigError&) {
      throw;
    } catch (const PluginBug& e) {  // the component's code is wrong, not the task file
      throw ConfigError({Diagnostic{Location{n->config.type->origin, 0, 0}, e.what()}});
    } catch (const DeviceError& e) {
      error = e.what();
      device = true;
    } catch (const std::exception& e) {
      error = e.what();
    } catch (...) {
      error = "it threw a non-exception (not derived from std::exception) from its constructor";
    }
    if (error.empty()) continue;
    if (stop_source_.stop_requested()) {
      // A constructor cut short by the stop (a device wait that gave up): not a configuration error.
      n->logger->info("construction stopped: {}", error);
      break;
    }
    // The actuators created so far may already hold a device: they go to their safe state, and
    // the results go with the error (the summary lists them as after a run).
    construct_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - constructing_since).count();
    const std::string what = device ? ") could not start its device: " : ") refused its configuration: ";
    throw ConstructionError({Diagnostic{n->config.where, "component '" + n->config.name + "' (" + n->spec.type_name() + what + error}},
                            safe_states_after_construction(), device ? Outcome::RuntimeError : Outcome::ConfigError);
  }
  construct_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - constructing_since).count();
  constructed_.store(true);
  // Stopped while constructing: the components not constructed stay so, and run() only takes the
  // safe states of those that were.
  if (stop_source_.stop_requested()) {
    std::string last;
    for (auto& n : nodes)
      if (!n->current_component()) {
        last = "component '" + n->config.name + "' (" + n->spec.type_name() + ")";
        break;
      }
    request_stop(Outcome::Interrupted, last.empty() ? "stop requested while constructing"
                                                    : "stop requested while constructing " + last);
  }
}

std::vector<SafeStateResult> Graph::safe_states_after_construction() {
  Watchdog safe;
  std::vector<SafeStateResult> safe_states;
  std::vector<std::pair<std::size_t, std::shared_ptr<SafeStateResult>>> started_calls;  // index in safe_states, result
  for (auto& a : nodes) {
    if (a->spec.kind() != Kind::Actuator) continue;
    safe_states.push_back({a->config.name, "not constructed", {}});
    if (!a->current_component()) continue;
    auto r = std::make_shared<SafeStateResult>();
    started_calls.emplace_back(safe_states.size() - 1, r);
    safe.start([a = a.get(), r] { *r = a->safe_state(); });
  }
  safe.wait_until(std::chrono::steady_clock::now() + grace());
  for (std::size_t k = 0; k < started_calls.size(); ++k) {
    auto& result = safe_states[started_calls[k].first];
    if (safe.returned(k)) result = *started_calls[k].second;
    else result = safe_state_not_returned(result.component);
  }
  return safe_states;
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

// ---------------------------------------------------------------------------------------------
// Watchdog

Watchdog::~Watchdog() {
  std::vector<char> done;
  {
    std::lock_guard lock(shared_->mutex);
    done = shared_->done;
  }
  for (std::size_t i = 0; i < threads_.size(); ++i) {
    if (!threads_[i].joinable()) continue;
    if (done[i])
      threads_[i].join();
    else
      threads_[i].detach();  // it holds `shared_` (and whatever f holds), never this object
  }
}

void Watchdog::start(std::function<void()> f) {
  std::size_t i = 0;
  {
    std::lock_guard lock(shared_->mutex);
    i = shared_->done.size();
    shared_->done.push_back(0);
  }
  auto finish = [s = shared_, i] {
    std::lock_guard lock(s->mutex);
    s->done[i] = 1;
    s->cv.notify_all();
  };
  auto fn = std::make_shared<std::function<void()>>(std::move(f));
  try {
    threads_.emplace_back([fn, finish] {
      prepare_thread_for_crash_reports();
      (*fn)();
      finish();
    });
  } catch (const std::system_error&) {  // no thread to spare: call it here, unguarded
    threads_.emplace_back();
    (*fn)();
    finish();
  }
}

void Watchdog::wait_until(std::chrono::steady_clock::time_point deadline) {
  std::unique_lock lock(shared_->mutex);
  shared_->cv.wait_until(lock, deadline, [this] {
    return std::all_of(shared_->done.begin(), shared_->done.end(), [](char d) { return d != 0; });
  });
}

bool Watchdog::returned(std::size_t i) {
  std::lock_guard lock(shared_->mutex);
  return shared_->done.at(i) != 0;
}

void prepare_thread_for_crash_reports() {
  struct AltStack {
    std::unique_ptr<char[]> memory;
    ~AltStack() {
      if (!memory) return;
      stack_t off{};
      off.ss_flags = SS_DISABLE;
      sigaltstack(&off, nullptr);  // before the memory goes
    }
  };
  thread_local AltStack alt;
  if (alt.memory) return;
  constexpr std::size_t kSize = 64 * 1024;
  alt.memory = std::make_unique<char[]>(kSize);
  stack_t ss{};
  ss.ss_sp = alt.memory.get();
  ss.ss_size = kSize;
  if (sigaltstack(&ss, nullptr) != 0) alt.memory.reset();
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
    if (waits.empty() && n->periodic() && !n->ticking.load())
      waits.push_back((std::ostringstream() << "its period of " << n->trigger.period_s << " s is beyond the run's clock (at most "
                                            << kMaxDurationS << " s): it will not tick again")
                          .str());
    if (waits.empty())
      for (auto& in : n->input_states)
        if (in->buffer && in->buffer->empty() && !in->closed()) waits.push_back("waiting on input '" + in->spec->name + "'");
    if (!waits.empty()) why << "; " << n->config.name << ": " << waits.front();
  }
  if (quiet()) request_stop(Outcome::RuntimeError, why.str());
}

void Graph::request_stop(Outcome outcome, const std::string& reason, std::shared_ptr<const Event> event) {
  stop_source_.request_stop();  // before the flag: a component that sees stopping() sees its token requested
  {
    std::lock_guard lock(result_mutex_);
    if (stopping_.load()) return;
    result_.outcome = outcome;
    result_.reason = reason;
    final_event_ = std::move(event);
    stopping_.store(true, std::memory_order_release);
  }
  if (executor_) executor_->wake_all();
}

void Graph::record_event(const Event& e) { record_event(std::make_shared<const Event>(e)); }

void Graph::record_event(std::shared_ptr<const Event> e) {
  std::lock_guard lock(result_mutex_);
  if (events_.size() < 10000) events_.push_back(std::move(e));
}

std::vector<Event> Graph::events() {
  std::lock_guard lock(result_mutex_);
  std::vector<Event> out;
  out.reserve(events_.size());
  for (const auto& e : events_) out.push_back(*e);
  return out;
}

void Graph::deliver(const EventRule& rule, const std::shared_ptr<const Event>& e, const Header& header) {
  Node& dst = node(rule.target);
  for (auto& in : dst.input_states)
    if (in->spec->name == rule.target_port) {
      in->buffer->push(Packet::make<Event>(e, header));
      notify(&dst);
      return;
    }
}

void Graph::end_ticks(Node* n) {
  if (!n->ticking.exchange(false)) return;
  // The last timer gone may leave nothing that could wake the graph: let the executor look.
  if (live_periodic.fetch_sub(1) == 1 && executor_) executor_->poke();
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
  if (constructing_since == std::chrono::steady_clock::time_point{}) constructing_since = started;
  running_since_set_.store(true, std::memory_order_release);
  // Stopped before it started (while constructing): nothing runs, some components may not exist.
  if (!stopping()) {
    for (auto& n : nodes)
      if (n->periodic()) {
        n->ticking.store(true);
        live_periodic.fetch_add(1);
      }
    for (auto& n : nodes) notify(n.get());
  }
  executor_->run();  // returns once the graph is stopping
  const std::vector<StuckCall> stuck = stop();

  std::lock_guard lock(result_mutex_);
  RunResult r = result_;
  r.wall_s = wall_s_now();
  r.construct_s = construct_s;
  r.events.reserve(events_.size());
  for (std::size_t i = 0; i < events_.size(); ++i) {
    r.events.push_back(*events_[i]);
    if (events_[i] == final_event_) r.final_event_index = i;
  }
  if (final_event_) r.final_event = *final_event_;
  r.stuck = stuck;
  r.safe_states = safe_states_;
  const std::uint64_t left = collect_stats(r);
  if (left > 0) make_logger("runtime")->info("{} samples were still queued at the stop (see 'left' per connection in the summary)", left);
  return r;
}

// Per-component and per-connection counts as they stand; callable while the task runs (every
// count read is atomic or taken under its buffer's lock). Returns the samples queued now.
std::uint64_t Graph::collect_stats(RunResult& r) {
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
    s.lost_to_restarts = n->lost_to_restarts;
    r.lost_to_restarts += n->lost_to_restarts;
    if (n->finished.load())
      s.state = "finished";
    else
      switch (n->state.load()) {
        case Node::Idle: s.state = "idle"; break;
        case Node::Queued: s.state = "queued"; break;
        default: s.state = "running"; break;
      }
    {
      std::lock_guard stage_lock(n->stage_mutex);
      s.stage = n->stage;
      if (!s.stage.empty()) n->count_stage_time();  // the current stage, up to now
      for (const auto& name : n->spec.stage_names()) s.stages.emplace_back(name, n->stage_times[name]);
      s.results = n->results;
    }
    r.components.push_back(std::move(s));
  }
  std::uint64_t left = 0;
  for (auto& b : buffers) {
    if (b->tap || !b->consumer) continue;
    const std::uint64_t queued = b->queued();
    BufferLock block(*b);
    ConnectionStats c{b->from, b->to, b->policy, b->pushed, b->consumed, b->dropped, queued, b->peak, b->peak_bytes};
    c.capacity = b->policy == BufferPolicy::Latest ? 1 : b->capacity;
    r.connections.push_back(std::move(c));
    left += queued;
  }
  return left;
}

RunResult Graph::snapshot() {
  RunResult r;
  if (running_since_set_.load(std::memory_order_acquire)) {
    r.wall_s = wall_s_now();
    r.construct_s = construct_s;
  }
  collect_stats(r);
  // The calls running now and each actuator's safe state so far: what an exit that does not wait
  // (a second Ctrl-C) leaves behind, for its summary.
  static constexpr const char* kProgress[] = {"not attempted", "did not return", "reached", "failed"};
  for (auto& n : nodes) {
    const bool actuator = n->spec.kind() == Kind::Actuator;
    const int progress = actuator ? std::clamp(n->safe_state_progress.load(), 0, 3) : 0;
    if (const char* call = n->call.load(std::memory_order_acquire)) r.stuck.push_back({n->config.name, n->spec.type_name(), call});
    else if (progress == 1) r.stuck.push_back({n->config.name, n->spec.type_name(), "safe_state()"});
    if (actuator) r.safe_states.push_back({n->config.name, kProgress[progress], ""});
  }
  return r;
}

std::chrono::steady_clock::duration Graph::grace() const {
  const double s = std::min(std::max(0.0, options.stop_grace_s), kMaxDurationS);  // NaN: 0
  return std::chrono::nanoseconds(static_cast<std::int64_t>(s * 1e9));
}

double Graph::wall_s_now() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - constructing_since).count();
}

std::vector<StuckCall> Graph::stop() {
  using Clock = std::chrono::steady_clock;
  const auto grace = this->grace();
  // Ask running (and blocking) components to return. interrupt() may block too: each call gets
  // a thread of its own, so a stuck one is only reported.
  Watchdog interrupts;
  std::vector<Node*> interrupted;
  for (auto& n : nodes)
    if (n->current_component() && (n->call.load(std::memory_order_acquire) != nullptr || n->spec.is_blocking())) {
      interrupted.push_back(n.get());
      interrupts.start([n = n.get()] { n->interrupt(); });
    }
  const auto deadline = Clock::now() + grace;

  // Every actuator goes to its safe state as soon as its own call returned (so that safe_state()
  // does not overlap its process()), without waiting for the other components' threads: one of
  // them may be stuck, and a second Ctrl-C meanwhile would leave the actuators unsafe. In
  // parallel, each under its own watchdog; one still in its own call at the deadline gets it then.
  // One whose spec allows it (Spec::concurrent_safe_state) gets it at once, beside its call.
  Watchdog safe;
  std::vector<Node*> actuators;
  std::vector<std::shared_ptr<SafeStateResult>> results;
  std::vector<std::size_t> watch;  // the watchdog's index of each actuator's call, once started
  for (auto& n : nodes)
    if (n->spec.kind() == Kind::Actuator) {
      actuators.push_back(n.get());
      results.push_back(std::make_shared<SafeStateResult>());
      watch.push_back(SIZE_MAX);
    }
  // An actuator that is being interrupted goes safe once its interrupt() returned: a driver's
  // interrupt() cuts its waits on the device, and arriving during safe_state() it would cut those.
  std::vector<std::size_t> interrupt_of(actuators.size(), SIZE_MAX);
  for (std::size_t i = 0; i < actuators.size(); ++i)
    for (std::size_t k = 0; k < interrupted.size(); ++k)
      if (interrupted[k] == actuators[i]) interrupt_of[i] = k;
  std::size_t started_safe = 0;
  auto start_safe_states = [&](bool even_running) {
    for (std::size_t i = 0; i < actuators.size(); ++i) {
      if (watch[i] != SIZE_MAX) continue;
      // Neither Running nor RunningNotified (running, and notified during the call): no strand
      // holds it, and a strand that starts now sees the stop first.
      const int state = actuators[i]->state.load(std::memory_order_seq_cst);
      const bool in_call = state == Node::Running || state == Node::RunningNotified;
      const bool at_once = actuators[i]->spec.has_concurrent_safe_state();
      if (!even_running && !at_once && (in_call || (interrupt_of[i] != SIZE_MAX && !interrupts.returned(interrupt_of[i])))) continue;
      watch[i] = started_safe++;
      safe.start([n = actuators[i], r = results[i]] { *r = n->safe_state(); });
    }
  };
  for (start_safe_states(false); started_safe < actuators.size() && Clock::now() < deadline; start_safe_states(false))
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  const bool joined = executor_->join(std::max(0.0, std::chrono::duration<double>(deadline - Clock::now()).count()));
  interrupts.wait_until(deadline);
  start_safe_states(true);
  safe.wait_until(Clock::now() + grace);

  std::vector<StuckCall> stuck;
  for (auto& n : nodes)
    if (const char* call = n->call.load(std::memory_order_acquire)) stuck.push_back({n->config.name, n->spec.type_name(), call});
  for (std::size_t i = 0; i < interrupted.size(); ++i)
    if (!interrupts.returned(i))
      stuck.push_back({interrupted[i]->config.name, interrupted[i]->spec.type_name(), "interrupt()"});
  std::vector<SafeStateResult> safe_states;
  for (std::size_t i = 0; i < actuators.size(); ++i) {
    if (safe.returned(watch[i])) {
      safe_states.push_back(*results[i]);
      continue;
    }
    stuck.push_back({actuators[i]->config.name, actuators[i]->spec.type_name(), "safe_state()"});
    safe_states.push_back(safe_state_not_returned(actuators[i]->config.name));
  }
  if (!joined && stuck.empty()) stuck.push_back({"", "", "a runtime thread"});
  if (!stuck.empty()) abandoned.store(true);

  std::lock_guard lock(result_mutex_);
  safe_states_ = safe_states;
  for (const auto& s : safe_states) {
    if (s.status != "failed" || result_.outcome != Outcome::Success) continue;
    result_.outcome = Outcome::RuntimeError;
    result_.reason = "component '" + s.component + "' could not reach a safe state: " + s.message;
  }
  if (!stuck.empty()) {
    // The run cannot end cleanly with a call still running: a runtime error that names it.
    std::string why;
    for (const auto& c : stuck) {
      if (!why.empty()) why += "; ";
      if (c.component.empty())
        why += "a runtime thread did not return";
      else
        why += "component '" + c.component + "' (" + c.type + ") did not return from " + c.call;
    }
    char grace_text[32];
    std::snprintf(grace_text, sizeof grace_text, "%g", options.stop_grace_s);
    why += " within " + std::string(grace_text) + " s of the stop; left running";
    if (!result_.reason.empty()) why = result_.reason + "; then " + why;
    // An interrupted run stays interrupted (130 or 143): a script that runs fba-run in a loop
    // must see that its user stopped it. The reason names what was left running.
    if (result_.outcome != Outcome::Interrupted) result_.outcome = Outcome::RuntimeError;
    result_.reason = why;
  }
  return stuck;
}

void Graph::emergency_safe_states() noexcept {
  for (auto& n : nodes)
    if (n->spec.kind() == Kind::Actuator) {
      try {
        n->safe_state();
      } catch (...) {  // the result's strings could not be made: nothing more to do
      }
    }
}

std::string Graph::safe_states_so_far() const {
  static constexpr const char* kProgress[] = {"not attempted", "attempted, did not return", "reached", "failed"};
  std::string s;
  for (const auto& n : nodes)
    if (n->spec.kind() == Kind::Actuator) {
      if (!s.empty()) s += ", ";
      s += n->config.name + " (" + kProgress[std::clamp(n->safe_state_progress.load(), 0, 3)] + ")";
    }
  return s.empty() ? "no actuators" : s;
}

void Graph::warn_stall(double quiet_s) {
  if (stopping()) return;
  const double now_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  std::ostringstream why;
  why << "no component has produced anything for " << quiet_s << " s";
  double next_tick_s = -1;
  for (auto& n : nodes) {
    if (n->finished.load() || !n->periodic()) continue;
    const double last = static_cast<double>(n->last_tick_ns.load()) * 1e-9;
    const double in_s = std::max(0.0, (last < 0 ? 0 : last) + n->trigger.period_s - now_s);
    why << "; the next tick of periodic '" << n->config.name << "' is " << in_s << " s away";
    if (next_tick_s < 0 || in_s < next_tick_s) next_tick_s = in_s;
  }
  for (auto& n : nodes)
    if (n->is_sensor && !n->periodic() && !n->finished.load() && n->trigger.policy == TriggerPolicy::Free)
      why << "; the free-running sensor '" << n->config.name << "' runs but produces nothing";
  if (timeout_s > 0) {
    const double left = std::max(0.0, timeout_s - now_s);
    why << "; the run times out in " << left << " s";
    if (next_tick_s > left) why << ", before anything can happen";
  } else if (next_tick_s < 0) {
    why << "; nothing may ever happen: stop it (Ctrl-C) or give --timeout";
  } else {
    why << "; stop it (Ctrl-C) or give --timeout";
  }
  const std::string text = why.str();
  make_logger("fba")->warn("{}", text);
  record_event(Event{"fba", "stall_warning", text, now_ns()});
}

}  // namespace fba::detail

namespace fba {

Task::Task(const TaskConfig& config, RunOptions options)
    : graph_(std::make_unique<detail::Graph>(config, std::move(options))) {
  graph_->construct();
}
Task::~Task() {
  if (!graph_->abandoned.load()) return;
  // Threads left in component calls use the graph: keep it (and the plugins) for good. Held by a
  // global so that it is not reported as a leak.
  static std::mutex mutex;
  static auto* kept = new std::vector<std::unique_ptr<detail::Graph>>;
  std::lock_guard lock(mutex);
  kept->push_back(std::move(graph_));
}
const std::vector<Packet>& Task::tap(const std::string& port, std::size_t keep) { return graph_->tap(port, keep); }
RunResult Task::run() { return graph_->run(); }
void Task::request_stop(Outcome outcome, const std::string& reason) { graph_->request_stop(outcome, reason); }
void Task::emergency_safe_states() noexcept { graph_->emergency_safe_states(); }
std::string Task::safe_states_so_far() const { return graph_->safe_states_so_far(); }
RunResult Task::snapshot() const { return graph_->snapshot(); }

ActiveCall active_call() noexcept {
  const detail::Node* n = detail::t_active_node;
  if (!n) return {};
  return {n->config.name.c_str(), n->spec.type_name().c_str(), detail::t_active_call};
}

}  // namespace fba
