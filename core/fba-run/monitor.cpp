// fba-run's Monitor (see monitor.hpp): a std::jthread that waits on a condition variable between
// ticks, so that stop() ends it at once rather than at the next tick, and SIGUSR1's sample is taken
// without waiting for one either.
#include "monitor.hpp"

#include <exception>
#include <stdexcept>
#include <utility>

#include "fba/log.hpp"

namespace fba_run {

using Clock = std::chrono::steady_clock;

Monitor::Monitor(std::function<fba::RunResult()> sample) : sample_(std::move(sample)) {}

Monitor::~Monitor() { stop(); }

void Monitor::watch(Watcher watcher, Schedule schedule) {
  if (thread_.joinable()) throw std::logic_error("Monitor::watch after start()");
  if (schedule.every < Duration::zero()) throw std::invalid_argument("Monitor::watch: a negative period");
  entries_.push_back({std::move(watcher), schedule, std::nullopt, {}});
}

void Monitor::watch(Watcher watcher) { watch(std::move(watcher), Schedule{}); }

void Monitor::start(Duration period) {
  if (period <= Duration::zero()) throw std::invalid_argument("Monitor::start: the period must be above zero");
  if (thread_.joinable()) throw std::logic_error("Monitor::start called twice");
  period_ = period;
  const auto now = Clock::now();
  for (auto& e : entries_)  // the first call at the first tick, then every `every`
    e.due = e.schedule.every == kOnRequest ? Clock::time_point::max() : now;
  thread_ = std::jthread([this](std::stop_token stop) { loop(stop); });
}

void Monitor::request_sample() {
  {
    std::lock_guard lock(mutex_);
    requested_ = true;
  }
  wake_.notify_one();
}

void Monitor::stop() {
  if (!thread_.joinable()) return;
  thread_.request_stop();  // wakes the wait below through its stop token
  thread_.join();
}

void Monitor::finish(const fba::RunResult& final_result) {
  stop();
  for (auto& e : entries_) {
    if (!e.schedule.at_end || !e.watcher) continue;
    e.previous.reset();  // the final result's rates are over the whole run
    call(e, final_result);
  }
}

// A watcher that throws is said once and called no more: the run goes on without that view.
void Monitor::call(Entry& e, const fba::RunResult& now) {
  try {
    e.watcher(now, e.previous ? &*e.previous : nullptr);
    e.previous = now;
  } catch (const std::exception& ex) {
    fba::make_logger("fba-run")->error("a view of the running task failed and is stopped: {}", ex.what());
    e.watcher = nullptr;
  }
}

void Monitor::loop(std::stop_token stop) {
  auto next_tick = Clock::now() + period_;
  for (;;) {
    bool requested = false;
    {
      std::unique_lock lock(mutex_);
      wake_.wait_until(lock, stop, next_tick, [this] { return requested_; });
      if (stop.stop_requested()) return;
      requested = std::exchange(requested_, false);
    }
    const auto now = Clock::now();
    // A schedule counts from the tick it was called at, not from when the thread woke: a watcher
    // called every period is due at every tick, however late the wake-up.
    auto called_at = now;
    if (now >= next_tick) {
      called_at = next_tick;
      next_tick += period_;
      if (next_tick <= now) next_tick = now + period_;  // fell behind (a slow watcher): no burst
    }
    bool due = requested;
    for (const auto& e : entries_) due = due || (e.watcher && e.due <= now);
    if (!due) continue;
    const fba::RunResult sample = sample_();
    for (auto& e : entries_) {
      if (!e.watcher || (!requested && e.due > now)) continue;
      call(e, sample);
      if (e.schedule.every != kOnRequest) e.due = called_at + e.schedule.every;
    }
  }
}

}  // namespace fba_run
