// The two executors: threaded (a small pool of workers running nodes as strands, plus a thread
// for each blocking node) and deterministic (one thread, FIFO order, virtual clock).
#include <algorithm>
#include <condition_variable>
#include <cstdlib>
#include <queue>
#include <thread>

#include "fba/message_text.hpp"
#include "graph.hpp"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define FBA_CPU_RELAX() _mm_pause()
#else
#define FBA_CPU_RELAX() std::this_thread::yield()
#endif

namespace fba::detail {
namespace {

using Clock = std::chrono::steady_clock;

// The deterministic executor ends a run as stalled after this many stall warnings' worth of task
// time (RunOptions::stall_warning_s; ten minutes by default) with only timers firing.
constexpr double kDeterministicQuietWarnings = 60;

struct Timer {
  std::int64_t deadline_ns;
  std::size_t order;  // ties break by node order, so the deterministic executor stays deterministic
  Node* node;
  bool operator>(const Timer& o) const {
    return deadline_ns != o.deadline_ns ? deadline_ns > o.deadline_ns : order > o.order;
  }
};
using TimerQueue = std::priority_queue<Timer, std::vector<Timer>, std::greater<>>;

// kNeverNs for a period beyond the clock's range: the node's next tick never comes in this run.
std::int64_t period_ns(const Node& n) { return std::max<std::int64_t>(1, duration_ns(n.trigger.period_s)); }

// The time-out as a nanosecond count, or kNeverNs for none (0, or too long to represent).
std::int64_t timeout_ns(const Graph& g) { return g.timeout_s > 0 ? duration_ns(g.timeout_s) : kNeverNs; }

// ---------------------------------------------------------------------------------------------

class ThreadedExecutor final : public Executor {
 public:
  ThreadedExecutor(Graph& g, int threads) : g_(g) {
    const int cores = static_cast<int>(std::max(2u, std::thread::hardware_concurrency()));
    threads_ = threads > 0 ? threads : cores;
    // Spinning pays only while a spinner has a core to itself; the others sleep until woken.
    spin_limit_ = std::max(1, std::min(threads_, cores) / 2);
    for (auto& n : g_.nodes)
      if (n->dedicated) {
        n->executor_slot = dedicated_.size();
        dedicated_.push_back(std::make_unique<Dedicated>(n.get()));
      }
  }

  void enqueue(Node* n) override {
    if (n->dedicated) {
      Dedicated& d = *dedicated_[n->executor_slot];
      d.signal.fetch_add(1, std::memory_order_seq_cst);
      d.signal.notify_one();
      return;
    }
    bool wake = false;
    {
      std::lock_guard lock(queue_mutex_);
      queue_.push_back(n);
      queued_.store(queue_.size(), std::memory_order_seq_cst);
      // Spinning workers pick up what they see, and woken ones are on their way: wake one
      // sleeper per node beyond those, never all of them. Only a sleeper not already woken can
      // be woken: a wake-up counted beyond them would never be consumed, and the next node
      // would then wait in the queue with every worker asleep.
      if (waking_ < sleepers_ && queue_.size() > static_cast<std::size_t>(spinners_ + waking_)) {
        ++waking_;
        wake = true;
      }
    }
    if (wake) work_cv_.notify_one();
  }

  std::int64_t now_ns() const override {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - start_).count();
  }

  void wake_all() override {
    {
      std::lock_guard lock(queue_mutex_);  // a worker between its stop check and its wait gets the notification
    }
    work_cv_.notify_all();
    for (auto& d : dedicated_) {
      d->signal.fetch_add(1);
      d->signal.notify_one();
    }
    {
      std::lock_guard lock(timer_mutex_);
      timer_cv_.notify_all();
    }
    poke();
  }

  void poke() override {
    std::lock_guard lock(main_mutex_);
    poked_ = true;
    main_cv_.notify_one();
  }

  void run() override {
    for (auto& n : g_.nodes)
      if (n->periodic()) timers_.push(Timer{0, timers_.size(), n.get()});
    // A thread that cannot be created (out of threads or memory) stops the run like any runtime
    // error; the threads already started see the stop and are joined (or left) by join().
    std::string starting;
    try {
      for (int i = 0; i < threads_; ++i) {
        starting = "worker thread " + std::to_string(i + 1) + " of " + std::to_string(threads_);
        workers_.emplace_back([this] { prepare_thread_for_crash_reports(); worker(); });
      }
      for (auto& d : dedicated_) {
        starting = "the thread of component '" + d->node->config.name + "'";
        d->thread = std::thread([this, d = d.get()] { prepare_thread_for_crash_reports(); dedicated(*d); });
        ++dedicated_started_;
      }
      starting = "the timer thread";
      timer_thread_ = std::thread([this] { timers(); });
    } catch (const std::exception& e) {
      g_.request_stop(Outcome::RuntimeError, "could not start " + starting + ": " + e.what() +
                                                 " (the system's limit on threads or memory was reached)");
    }

    const std::int64_t limit_ns = timeout_ns(g_);
    const bool limited = limit_ns != kNeverNs;
    const auto deadline = g_.started + std::chrono::nanoseconds(limited ? limit_ns : 0);
    const auto stall = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(std::max(0.001, g_.options.stall_warning_s)));
    auto progress = g_.progress();
    auto quiet_since = Clock::now();
    std::unique_lock lock(main_mutex_);
    while (!g_.stopping()) {
      auto woken = [this] { return poked_ || g_.stopping(); };
      const auto wake_at = limited ? std::min(deadline, quiet_since + stall) : quiet_since + stall;
      main_cv_.wait_until(lock, wake_at, woken);
      if (g_.stopping()) break;
      const auto now = Clock::now();
      if (limited && now >= deadline) {
        lock.unlock();
        g_.request_stop(Outcome::RuntimeError, "timed out after " + number_text(g_.timeout_s) + " s");
        lock.lock();
        continue;
      }
      if (g_.progress() != progress) {
        progress = g_.progress();
        quiet_since = now;
      } else if (now >= quiet_since + stall) {
        lock.unlock();
        g_.warn_stall(std::chrono::duration<double>(now - quiet_since).count());
        lock.lock();
        quiet_since = now;  // again after another quiet period
      }
      if (poked_ && !g_.stopping()) {
        poked_ = false;
        lock.unlock();
        g_.check_idle();
        lock.lock();
      }
    }
  }

  bool join(double grace_s) override {
    wake_all();
    const std::uint32_t total = static_cast<std::uint32_t>(workers_.size() + dedicated_started_);
    const auto until = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(grace_s));
    while (exited_.load() < total && Clock::now() < until) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    const bool all = exited_.load() >= total;
    // Which thread is stuck is not known here, only that one is: the graph names the component
    // call. A thread left behind holds the graph, which then is never destroyed.
    auto finish = [all](std::thread& t) {
      if (!t.joinable()) return;
      if (all)
        t.join();
      else
        t.detach();
    };
    for (auto& w : workers_) finish(w);
    for (auto& d : dedicated_) finish(d->thread);
    if (timer_thread_.joinable()) timer_thread_.join();  // waits on the stop flag only
    return all;
  }

 private:
  struct Dedicated {
    explicit Dedicated(Node* n) : node(n) {}
    Node* node;
    std::atomic<std::uint32_t> signal{0};
    std::thread thread;
  };

  void worker() {
    constexpr int kSpins = 2000;  // pause instructions: tens of microseconds, less than a wake-up
    std::unique_lock lock(queue_mutex_);
    bool spun = false;
    while (!g_.stopping()) {
      if (!queue_.empty()) {
        Node* n = queue_.front();
        queue_.pop_front();
        queued_.store(queue_.size(), std::memory_order_seq_cst);
        lock.unlock();
        g_.run_strand(n);
        lock.lock();
        spun = false;
        continue;
      }
      // A hop that arrives within microseconds costs no system call on either side, but only a
      // few workers spin: with more workers than cores, spinners would take the cores from the
      // workers with something to do.
      if (!spun && spinners_ < spin_limit_) {
        ++spinners_;
        lock.unlock();
        for (int i = 0; i < kSpins && queued_.load(std::memory_order_relaxed) == 0 && !g_.stopping(); ++i)
          FBA_CPU_RELAX();
        lock.lock();
        --spinners_;
        spun = true;
        continue;
      }
      ++sleepers_;
      work_cv_.wait(lock);
      --sleepers_;
      if (waking_ > 0) --waking_;
      spun = false;
    }
    lock.unlock();
    exited_.fetch_add(1);
    exited_.notify_all();
  }

  void dedicated(Dedicated& d) {
    std::uint32_t seen = 0;
    while (!g_.stopping()) {
      const auto now = d.signal.load();
      if (now == seen) {
        d.signal.wait(seen);
        continue;
      }
      seen = now;
      if (d.node->state.load() == Node::Queued) g_.run_strand(d.node);
    }
    exited_.fetch_add(1);
    exited_.notify_all();
  }

  void timers() {
    std::unique_lock lock(timer_mutex_);
    while (!g_.stopping() && !timers_.empty()) {
      const Timer t = timers_.top();
      const auto due = start_ + std::chrono::nanoseconds(t.deadline_ns);
      if (Clock::now() < due) {
        timer_cv_.wait_until(lock, due, [this] { return g_.stopping(); });
        continue;
      }
      timers_.pop();
      if (t.node->finished.load()) continue;
      t.node->tick_pending.store(true, std::memory_order_seq_cst);  // before notify's state load
      g_.notify(t.node);
      // Fixed rate; ticks that could not be served in time are skipped, not queued up.
      const std::int64_t period = period_ns(*t.node), now = now_ns();
      std::int64_t next = add_ns(t.deadline_ns, period);
      if (next < now) next = add_ns(now, period);
      if (next == kNeverNs) {
        g_.end_ticks(t.node);  // beyond the clock's range: no more ticks in this run
        continue;
      }
      timers_.push(Timer{next, t.order, t.node});
    }
  }

  Graph& g_;
  int threads_ = 2;
  const Clock::time_point start_ = Clock::now();
  // Priority-inheriting locks (pi_mutex.hpp): workers take them on every hop. The condition
  // variables must then be the _any kind; waking is not priority-ordered, the lock hand-off is.
  PiMutex queue_mutex_;
  std::deque<Node*> queue_;
  std::atomic<std::size_t> queued_{0};  // queue_.size(), for spinners to watch without the lock
  std::condition_variable_any work_cv_;
  int spin_limit_ = 1;
  int spinners_ = 0, sleepers_ = 0, waking_ = 0;  // under queue_mutex_; waking_ <= sleepers_
  std::size_t dedicated_started_ = 0;
  std::atomic<std::uint32_t> exited_{0};
  std::vector<std::thread> workers_;
  std::vector<std::unique_ptr<Dedicated>> dedicated_;
  std::thread timer_thread_;
  PiMutex timer_mutex_;
  std::condition_variable_any timer_cv_;
  TimerQueue timers_;
  PiMutex main_mutex_;
  std::condition_variable_any main_cv_;
  bool poked_ = false;
};

// ---------------------------------------------------------------------------------------------

class DeterministicExecutor final : public Executor {
 public:
  explicit DeterministicExecutor(Graph& g) : g_(g) {}

  void enqueue(Node* n) override { queue_.push_back(n); }
  std::int64_t now_ns() const override { return virtual_ns_.load(std::memory_order_relaxed); }
  void wake_all() override {
    std::lock_guard lock(mutex_);
    cv_.notify_all();
  }
  void poke() override {}

  // The loop runs on a thread of its own, so that a component that never returns cannot hold
  // the stop (and the timeout) back: the caller waits here for either.
  void run() override {
    try {
      thread_ = std::thread([this] {
        prepare_thread_for_crash_reports();
        loop();
        std::lock_guard lock(mutex_);
        done_ = true;
        cv_.notify_all();
      });
    } catch (const std::system_error& e) {
      g_.request_stop(Outcome::RuntimeError, std::string("could not start the executor's thread: ") + e.what());
      return;
    }
    const std::int64_t limit_ns = timeout_ns(g_);
    const auto deadline = g_.started + std::chrono::nanoseconds(limit_ns == kNeverNs ? 0 : limit_ns);
    std::unique_lock lock(mutex_);
    auto woken = [this] { return done_ || g_.stopping(); };
    while (!woken()) {
      if (limit_ns == kNeverNs) {
        cv_.wait(lock, woken);
      } else if (!cv_.wait_until(lock, deadline, woken)) {
        lock.unlock();
        g_.request_stop(Outcome::RuntimeError, "timed out after " + number_text(g_.timeout_s) + " s");
        lock.lock();
      }
    }
  }

  bool join(double grace_s) override {
    if (!thread_.joinable()) return true;
    std::unique_lock lock(mutex_);
    const bool done = cv_.wait_for(lock, std::chrono::duration<double>(grace_s), [this] { return done_; });
    lock.unlock();
    if (done)
      thread_.join();
    else
      thread_.detach();
    return done;
  }

 private:
  void loop() {
    TimerQueue timers;
    for (std::size_t i = 0; i < g_.nodes.size(); ++i)
      if (g_.nodes[i]->periodic()) timers.push(Timer{0, i, g_.nodes[i].get()});
    const auto wall_start = Clock::now();
    std::uint64_t steps = 0;
    const std::int64_t limit_ns = timeout_ns(g_);
    // Nothing outside the run moves a virtual clock: when only timers have fired for this long of
    // task time, no component producing anything, the run waits for what will not come (a port
    // left unwired, a state never sent) and would spin through ticks for ever.
    const double quiet_limit_s = kDeterministicQuietWarnings * std::max(0.001, g_.options.stall_warning_s);
    std::uint64_t progress = g_.progress();
    std::int64_t quiet_since_ns = 0;
    while (!g_.stopping()) {
      if (limit_ns != kNeverNs && (++steps & 255) == 0 && Clock::now() - wall_start > std::chrono::nanoseconds(limit_ns)) {
        g_.request_stop(Outcome::RuntimeError, "timed out after " + number_text(g_.timeout_s) + " s");
        break;
      }
      if (!queue_.empty()) {
        Node* n = queue_.front();
        queue_.pop_front();
        g_.run_strand(n);
        continue;
      }
      g_.check_idle();
      if (g_.stopping()) break;
      // Nothing to run: time jumps to the next tick.
      while (!timers.empty() && timers.top().node->finished.load()) timers.pop();
      if (timers.empty()) {
        g_.request_stop(Outcome::RuntimeError, "stalled: no component can run and no timer is pending");
        break;
      }
      const Timer t = timers.top();
      timers.pop();
      virtual_ns_.store(std::max(virtual_ns_.load(std::memory_order_relaxed), t.deadline_ns),
                        std::memory_order_relaxed);
      if (g_.progress() != progress) {
        progress = g_.progress();
        quiet_since_ns = t.deadline_ns;
      } else if (static_cast<double>(t.deadline_ns - quiet_since_ns) * 1e-9 >= quiet_limit_s) {
        std::string ticking;
        for (const auto& n : g_.nodes)
          if (n->periodic() && !n->finished.load()) ticking += (ticking.empty() ? "" : ", ") + n->config.name;
        g_.request_stop(Outcome::RuntimeError, "stalled: for " + number_text(quiet_limit_s) +
                                                   " s of task time no component produced anything, only the timers of " + ticking +
                                                   " fired; on the deterministic executor's clock nothing else can come");
        break;
      }
      t.node->tick_pending.store(true);
      g_.notify(t.node);
      const std::int64_t next = add_ns(t.deadline_ns, period_ns(*t.node));
      if (next == kNeverNs) g_.end_ticks(t.node);  // beyond the clock's range: no more ticks in this run
      else timers.push(Timer{next, t.order, t.node});
    }
  }

  Graph& g_;
  std::deque<Node*> queue_;
  std::atomic<std::int64_t> virtual_ns_{0};  // read by the stopping thread too (interrupt errors)
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable cv_;
  bool done_ = false;
};

}  // namespace

std::unique_ptr<Executor> make_threaded_executor(Graph& g, int threads) {
  return std::make_unique<ThreadedExecutor>(g, threads);
}
std::unique_ptr<Executor> make_deterministic_executor(Graph& g) {
  return std::make_unique<DeterministicExecutor>(g);
}

}  // namespace fba::detail
