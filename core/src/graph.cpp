// The graph: nodes wired by buffers as the task says, constructed, then run: nodes scheduled as
// strands when notified, the graph watched for idleness (every sensor done: success; nothing can
// run: a stall), events recorded and delivered, the counts collected for snapshots and the
// summary. The stop and the safe states are in shutdown.cpp, the executors in executors.cpp.
#include "graph.hpp"

#include <algorithm>
#include <sstream>

#include "fba/log.hpp"

namespace fba::detail {

std::int64_t duration_ns(double seconds) {
  if (!(seconds < kMaxDurationS)) return kNeverNs;  // NaN too
  return std::max<std::int64_t>(0, static_cast<std::int64_t>(seconds * 1e9));
}

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
    if (b->gating) from->gating_outputs.push_back(b.get());
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

OutputState& Graph::output(const std::string& port, const char* what) {
  const auto dot = port.rfind('.');
  if (dot == std::string::npos) throw std::invalid_argument(std::string(what) + " needs 'component.output', got '" + port + "'");
  Node& n = node(port.substr(0, dot));
  for (auto& out : n.output_states)
    if (out->spec->name == port.substr(dot + 1)) return *out;
  throw std::invalid_argument("component '" + n.config.name + "' has no output '" + port.substr(dot + 1) + "'");
}

std::vector<Packet>& Graph::tap(const std::string& port, std::size_t keep) {
  OutputState& out = output(port, "tap");
  taps.emplace_back();
  auto b = std::make_unique<Buffer>();
  b->tap = &taps.back();
  b->tap_keep = keep;
  b->from = port;
  b->to = "tap";
  out.consumers.push_back(b.get());
  buffers.push_back(std::move(b));
  return taps.back();
}

// Another consumer of the output, costing the other outputs nothing; the output pushes into it
// like into a `latest` connection (`drop_oldest` of `keep` to keep every sample), which holds no
// producer back (not gating).
std::shared_ptr<LatestSample> Graph::watch(const std::string& port, std::size_t keep) {
  if (ran_) throw std::logic_error("watch('" + port + "') after the task ran: call it before run()");
  OutputState& out = output(port, "watch");
  auto w = std::make_shared<LatestSample>(port, out.type, keep);
  out.consumers.push_back(&w->buffer());
  watches.push_back(w);
  return w;
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

// Per-component and per-connection counts as they stand; callable while the task runs. A
// connection's counts are atomics written under its buffer's lock and read here without it, so
// that sampling a running task never holds up a worker on the data path; read while it runs, they
// may be a sample apart (pushed = delivered + dropped + left holds once the workers have stopped).
// Returns the samples queued now.
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

double Graph::wall_s_now() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - constructing_since).count();
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
std::shared_ptr<LatestSample> Task::watch(const std::string& port, std::size_t keep) { return graph_->watch(port, keep); }
RunResult Task::run() { return graph_->run(); }
void Task::request_stop(Outcome outcome, const std::string& reason) { graph_->request_stop(outcome, reason); }
void Task::emergency_safe_states() noexcept { graph_->emergency_safe_states(); }
std::string Task::safe_states_so_far() const { return graph_->safe_states_so_far(); }
RunResult Task::snapshot() const { return graph_->snapshot(); }

}  // namespace fba
