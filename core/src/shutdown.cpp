// The end of a run: Graph::stop (running components interrupted, every actuator sent to its safe
// state as soon as it is out of its own call, threads joined within the grace, calls that did not
// return reported and left behind), the safe states after a constructor refused, the emergency
// ones after a crash, and the Watchdog those calls run under. Apart from the graph because it must
// hold when anything else went wrong: it trusts no component call to return.
#include <algorithm>
#include <cstdio>
#include <system_error>

#include "graph.hpp"

namespace fba::detail {

namespace {
// An actuator whose safe_state() was still running when the stop grace ran out.
SafeStateResult safe_state_not_returned(const std::string& component) {
  return {component, "did not return", "safe_state() did not return within the stop grace"};
}
}  // namespace

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

std::chrono::steady_clock::duration Graph::grace() const {
  const double s = std::min(std::max(0.0, options.stop_grace_s), kMaxDurationS);  // NaN: 0
  return std::chrono::nanoseconds(static_cast<std::int64_t>(s * 1e9));
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

}  // namespace fba::detail
