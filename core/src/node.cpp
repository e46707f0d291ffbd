// A node: one component and its ports. How it is constructed, when it is ready, one invocation
// (inputs taken, process() called and guarded), its failure and restart, its events and their
// rules, its stages. Apart from the graph, which decides when a node runs; this file is what runs.
#include "node.hpp"

#include <algorithm>
#include <unordered_set>

#include "fba/log.hpp"
#include "fba/message_text.hpp"
#include "graph.hpp"

namespace fba::detail {

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

Node::Node(Graph& g, const ComponentConfig& c)
    : graph(g), config(c), spec(c.type->spec), trigger(c.trigger), is_sensor(spec.kind() == Kind::Sensor),
      timed(!spec.stage_names().empty()),
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

// Runs f, catching everything; returns what it threw, worded for "component 'x' (type) ...", or
// nothing (an optional, not an empty string: no string made and destroyed on every call).
// The exception's text may echo a parameter from the task file: its control bytes are escaped.
template <class F>
std::optional<std::string> catch_all(const char* call, F&& f) {
  try {
    f();
    return std::nullopt;
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
std::optional<std::string> Node::guarded(const char* what, F&& f) {
  ActiveScope active(this, what);
  // Release, not sequentially consistent (an exchange: a third of a light hop): the stop reads it
  // to name calls still running and to interrupt those in a call, and a call it misses as it starts
  // is not waiting on anything yet; blocking components are interrupted in any case.
  call.store(what, std::memory_order_release);
  std::optional<std::string> error = catch_all(what, std::forward<F>(f));
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
  const auto error = catch_all("interrupt()", [&] { c->interrupt(); });
  if (!error) return;
  logger->error("{}", describe(*error));
  graph.record_event(Event{config.name, "error", *error, graph.now_ns()});
}

SafeStateResult Node::safe_state() {
  SafeStateResult r{config.name, "not constructed", {}};
  auto c = current_component();
  int expected = 0;
  if (!c || !safe_state_progress.compare_exchange_strong(expected, 1)) {
    if (c) r.status = "already attempted";
    return r;
  }
  ActiveScope active(this, "safe_state()");
  r.message = catch_all("safe_state()", [&] { c->safe_state(); }).value_or("");
  r.status = r.message.empty() ? "reached" : "failed";
  safe_state_progress.store(r.message.empty() ? 2 : 3);
  if (r.message.empty())
    logger->info("safe state reached");
  else
    logger->error("could not reach a safe state: {}", describe(r.message));
  return r;
}

[[gnu::always_inline]] inline bool Node::outputs_have_room() const {  // inlined: ready() asks before every call
  for (const Buffer* b : gating_outputs)
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

bool Node::take_inputs(std::uint64_t& taken) {
  auto take = [this](std::size_t i) {  // sets the input's has_, for this invocation
    Buffer* b = input_states[i]->buffer;
    bool was_full = false;
    Input& in = inputs[i];
    in.has_ = b && b->pop(in.current_, was_full);
    if (!in.has_) return false;
    ++input_states[i]->received;
    if (was_full && b->producer) graph.notify(b->producer);
    return true;
  };
  taken = 0;
  const std::size_t n = inputs.size();  // read once: the compiler cannot tell that a pop leaves it alone
  if (trigger.policy != TriggerPolicy::All) {
    for (std::size_t i = 0; i < n; ++i) taken += take(i) ? 1 : 0;
    return taken > 0;
  }
  for (auto& in : inputs) in.has_ = false;
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
  for (std::size_t i = 0; i < n; ++i) taken += take(i) ? 1 : 0;
  return true;
}

void Node::invoke() {
  const bool tick = periodic() && tick_pending.exchange(false, std::memory_order_acq_rel);
  bool has_input = false;
  for (const auto& in : input_states)
    if (in->buffer && !in->buffer->empty()) { has_input = true; break; }

  if (!is_sensor && !has_input && !tick && !eos_delivered && inputs_closed()) {
    eos_delivered = true;
    const auto error = guarded("end_of_stream()", [&] { component->end_of_stream(); });
    if (error) fail(*error);
    on_finish();
    return;
  }

  std::uint64_t taken = 0;
  const bool took = take_inputs(taken);
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
  emitted_in_call.store(false, std::memory_order_relaxed);
  // `component` is only replaced on this thread (a restart), so it is read here without the lock.
  // Only a type with stages has its calls timed (for the summary's time per stage): the two clock
  // reads and locks would be a tenth of a light component's hop.
  if (timed) {
    std::lock_guard lock(stage_mutex);
    busy_since = std::chrono::steady_clock::now();
  }
  const auto error = guarded("process()", [&] { component->process(); });
  if (timed) {
    std::lock_guard lock(stage_mutex);
    count_stage_time();
    busy_since.reset();
  }
  if (error)
    fail(*error, taken);
  else if (emitted_in_call.load(std::memory_order_relaxed))
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
    const auto error = catch_all("its constructor", [&] { construct(); });
    if (error)
      graph.request_stop(Outcome::RuntimeError,
                         "component '" + config.name + "' (" + spec.type_name() + ") could not be restarted: " + *error);
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

}  // namespace fba::detail

namespace fba {

ActiveCall active_call() noexcept {
  const detail::Node* n = detail::t_active_node;
  if (!n) return {};
  return {n->config.name.c_str(), n->spec.type_name().c_str(), detail::t_active_call};
}

}  // namespace fba
