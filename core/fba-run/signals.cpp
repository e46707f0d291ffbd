// fba-run's signals (see signals.hpp). Every stop signal is blocked from the program's first
// instruction and taken by one watcher thread with sigtimedwait, so no work happens in a signal
// handler but the crash handler's, which is best effort. Apart from the run because it holds
// whatever happens at any moment: before the task is loaded, while it runs, and after.
#include "signals.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <future>
#include <iostream>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "fba/log.hpp"
#include "fba/registry.hpp"
#include "console.hpp"
#include "monitor.hpp"
#include "run_state.hpp"
#include "summary_file.hpp"

namespace fba_run {

namespace {

// Every signal whose default action ends the process and that is delivered to the process as a
// whole rather than raised by a faulting instruction: each ends the run in order, as SIGINT does
// (safe states, summary, exit 128 + N). SIGUSR1 writes the live graph instead. The faults
// (SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGTRAP, SIGSYS) have the crash handler, which
// passes one sent by kill(2) on to the watcher.
std::vector<int> stop_signals() {
  std::vector<int> v{SIGHUP,  SIGINT,  SIGQUIT, SIGUSR1, SIGUSR2,   SIGPIPE, SIGALRM, SIGTERM,
                     SIGSTKFLT, SIGXCPU, SIGXFSZ, SIGVTALRM, SIGPROF, SIGIO,   SIGPWR};
  for (int sig = SIGRTMIN; sig <= SIGRTMAX; ++sig) v.push_back(sig);
  return v;
}
const int kFaultSignals[] = {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGTRAP, SIGSYS};

// A signal whose disposition is not the default when fba-run starts is left as it is: one ignored
// by whoever started it (nohup ignores SIGHUP) stays ignored, one a preloaded tool handles
// (a profiler's SIGPROF) stays its.
bool at_default(int sig) {
  struct sigaction old {};
  return sigaction(sig, nullptr, &old) == 0 && !(old.sa_flags & SA_SIGINFO) && old.sa_handler == SIG_DFL;
}

// A fault signal sent by kill(2), passed on by the crash handler to the watcher. Plain globals,
// constant-initialised, not members of State: the handler may run before any initialiser has (a
// signal pending since exec arrives when .preinit_array unblocks the faults), and building State
// from there ran libstdc++'s and libfba's code before their own initialisation.
constinit std::atomic<int> g_forwarded{0};
constinit std::atomic<pid_t> g_forwarded_pid{0};


// How long a forced exit waits for its summary to be written.
constexpr std::chrono::seconds kForcedSummaryWait{3};

// An exit forced by a second signal: names the safe states so far and writes the summary of the run
// as it stands (what was still running, the safe states), beside summary.json then renamed over it,
// so that main, if it is writing its own at that moment, cannot mix the two. On a thread of its own,
// waited for a bounded time: a task lock held by a stuck thread, or a writer stuck on a full or hung
// file system, must not hold the exit back. Returns when written, or when the wait is over.
void report_forced_exit(int sig) {
  auto done = std::make_shared<std::promise<void>>();
  std::thread([sig, done] {
    auto& st = state();
    // The task is not destroyed, nor the configuration replaced, while they are read.
    std::lock_guard lock(st.mutex);
    fba::RunResult r;
    std::string safe_states = "no component was constructed";
    if (fba::Task* task = st.task.load()) {
      r = task->snapshot();
      safe_states = task->safe_states_so_far();
    }
    std::fprintf(stderr, "fba-run: second %s while stopping: exiting now without waiting; safe states: %s\n",
                 signal_name(sig).c_str(), safe_states.c_str());
    r.outcome = fba::Outcome::Interrupted;
    const char* first_phase = st.signal_phase.load();
    r.phase = first_phase ? first_phase : st.phase.load();
    r.signal = sig;
    r.forced = true;
    r.reason = "interrupted by " + signal_name(st.signal.load()) + " while " + r.phase + "; a second " +
               signal_name(sig) + " forced the exit before the stop was over";
    if (!st.summary.empty()) {
      std::string error;
      try {
        const fs::path partial = st.summary.string() + ".forced";
        error = write_summary(r, partial);
        if (error.empty() && std::rename(partial.c_str(), st.summary.c_str()) != 0)
          error = st.summary.string() + ": " + std::strerror(errno);
      } catch (const std::exception& e) {
        error = e.what();
      }
      if (!error.empty()) std::fprintf(stderr, "fba-run: could not write the summary %s\n", error.c_str());
    }
    done->set_value();
  }).detach();
  if (done->get_future().wait_for(kForcedSummaryWait) != std::future_status::ready)
    std::fprintf(stderr, "fba-run: second %s: the summary was not written within %lld s; exiting without it\n",
                 signal_name(sig).c_str(), static_cast<long long>(kForcedSummaryWait.count()));
}

// Whether a signal the watcher took asks for nothing: main's wake-up, or the kernel's notice to a
// writer of this process that its pipe's reader went away (SIGPIPE) or that a file grew past its
// limit (SIGXFSZ), which the write's own error reports where it was made. Each comes from this
// process itself; the same signals sent by another process are stop requests.
bool not_a_request(const siginfo_t& info) {
  const int sig = info.si_signo;
  return info.si_pid == getpid() && (sig == kWakeSignal || sig == SIGPIPE || sig == SIGXFSZ);
}

// Async-signal-safe pieces for the crash handler.
void say(const char* s) {
  if (!s) return;
  const auto written = ::write(2, s, std::strlen(s));
  (void)written;  // nothing more to do if stderr is gone
}

// SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGTRAP, SIGSYS: name what ran, attempt the safe states, write what can be
// written, exit 3. Best effort: after a crash the process may be too damaged for any of it.
void on_crash(int sig, siginfo_t* info, void*) {
  // Sent by another process (kill -SEGV): a request to stop, not a fault; the watcher takes it.
  if (info && (info->si_code == SI_USER || info->si_code == SI_QUEUE) && info->si_pid != getpid()) {
    g_forwarded_pid.store(info->si_pid);
    g_forwarded.store(sig);
    return;
  }
  static std::atomic<bool> once{false};
  if (once.exchange(true)) _exit(kRuntimeError);  // crashed again while reporting
  const fba::ActiveCall call = fba::active_call();
  const char* plugin = fba::plugin_being_loaded();
  say("fba-run: fatal signal ");
  say(sig == SIGSEGV ? "SIGSEGV" : sig == SIGBUS ? "SIGBUS" : sig == SIGFPE ? "SIGFPE" : sig == SIGILL ? "SIGILL"
      : sig == SIGABRT ? "SIGABRT" : sig == SIGTRAP ? "SIGTRAP" : "SIGSYS");
  if (call.component) {
    say(" in component '");
    say(call.component);
    say("' (");
    say(call.type);
    say(") during ");
    say(call.call);
  } else if (plugin) {
    say(" while loading the plugin ");
    say(plugin);
  } else {
    say(" while ");
    say(state().phase.load());
  }
  say("; attempting the actuators' safe states (best effort)\n");
  // What follows may block on a lock the crashed code held: an alarm ends it in any case.
  struct sigaction give_up {};
  give_up.sa_handler = [](int) { _exit(kRuntimeError); };
  sigemptyset(&give_up.sa_mask);
  sigaction(SIGALRM, &give_up, nullptr);
  alarm(10);
  auto& st = state();
  if (fba::Task* task = st.task.load()) task->emergency_safe_states();
  std::string reason = std::string("fatal signal ") + strsignal(sig);
  if (call.component)
    reason += std::string(" in component '") + call.component + "' (" + call.type + ") during " + call.call;
  else if (plugin)
    reason += std::string(" while loading the plugin ") + plugin;
  auto r = early_result(fba::Outcome::RuntimeError, reason);
  if (fba::Task* task = st.task.load()) r.reason += "; safe states: " + task->safe_states_so_far();
  write_summary(r);
  _exit(kRuntimeError);
}


// Before any shared library's initialiser: the stop signals wait for the watcher from the
// program's first instruction (only the dynamic loader's own start comes earlier).
// The fault signals are unblocked (a supervisor may have blocked them all): a kill -SEGV pending
// since exec then reaches the crash handler, which passes it on as a stop request.
void block_stop_signals_early(int, char**, char**) {
  const sigset_t signals = taken_signals();
  sigprocmask(SIG_BLOCK, &signals, nullptr);
  install_crash_handlers();
  sigset_t faults;
  sigemptyset(&faults);
  for (int sig : kFaultSignals) sigaddset(&faults, sig);
  sigprocmask(SIG_UNBLOCK, &faults, nullptr);
}
[[gnu::section(".preinit_array"), gnu::used]] void (*const block_stop_signals_entry)(int, char**,
                                                                                     char**) = block_stop_signals_early;

}  // namespace

std::string signal_name(int sig) {
  if (sig >= SIGRTMIN && sig <= SIGRTMAX) return sig == SIGRTMIN ? "SIGRTMIN" : "SIGRTMIN+" + std::to_string(sig - SIGRTMIN);
  const char* abbrev = sigabbrev_np(sig);
  return abbrev ? std::string("SIG") + abbrev : "signal " + std::to_string(sig);
}

sigset_t taken_signals() {
  sigset_t set;
  sigemptyset(&set);
  for (int sig : stop_signals())
    if (at_default(sig)) sigaddset(&set, sig);
  return set;
}

[[noreturn]] void leave(int status) {
  std::fflush(stdout);
  std::fflush(stderr);
  std::cerr.flush();
  _exit(status);
}

bool interrupted_early(int& status) {
  auto& st = state();
  const int sig = st.signal.load();
  if (sig == 0) return false;
  const std::string reason = "interrupted by " + signal_name(sig) + " while " + st.signal_phase.load();
  const auto r = early_result(fba::Outcome::Interrupted, reason);
  const std::string error = write_summary(r);
  std::cerr << "fba-run: interrupted: " << reason << "\n";
  status = r.exit_code();
  if (!error.empty()) {
    std::cerr << "fba-run: could not write the summary " << error << "\n";
    status = kRuntimeError;
  }
  return true;
}

void request_live_graph() {
  auto& st = state();
  std::lock_guard lock(st.mutex);  // the monitor is not destroyed while asked
  if (st.live_dot.empty()) {
    std::fprintf(stderr, "fba-run: SIGUSR1: no --output-dir to write graph-live.dot into\n");
    return;
  }
  if (Monitor* monitor = st.monitor.load()) monitor->request_sample();  // none: nothing runs yet, or any more
}

void watch_signals(sigset_t signals) {
  auto& st = state();
  const timespec tick{0, 50'000'000};
  int first_sig = 0;
  pid_t first_pid = 0;
  std::chrono::steady_clock::time_point first_at;
  while (st.watching.load()) {
    siginfo_t info{};
    if (const int forwarded = g_forwarded.exchange(0)) {
      info.si_signo = forwarded;
      info.si_code = SI_USER;
      info.si_pid = g_forwarded_pid.load();
    } else if (sigtimedwait(&signals, &info, &tick) <= 0) {
      continue;
    }
    const int sig = info.si_signo;
    if (not_a_request(info)) continue;  // main is done (look at `watching` again), or a write's notice
    if (sig == SIGUSR1) {
      request_live_graph();
      continue;
    }
    // timeout(1) and group kills deliver one request twice: the same signal from the same process
    // within a second is that one request, not the second that forces the exit.
    const auto now = std::chrono::steady_clock::now();
    if (st.signals.load() > 0 && sig == first_sig && info.si_pid != 0 && info.si_pid == first_pid &&
        now - first_at < std::chrono::seconds(1))
      continue;
    if (st.signals.load() == 0) {
      first_sig = sig;
      first_pid = info.si_pid;
      first_at = now;
    }
    if (st.signals.fetch_add(1) > 0) {
      // A second signal forces the exit at once, with whatever safe states were attempted.
      report_forced_exit(sig);
      leave(128 + sig);
    }
    std::lock_guard lock(st.mutex);
    st.signal_phase.store(st.phase.load());
    st.signal.store(sig);
    const std::string said = "fba-run: " + signal_name(sig) + " received: stopping in order (a second one forces the exit)\n";
    if (Console* console = st.console.load()) console->above([&] { std::fputs(said.c_str(), stderr); });
    else std::fputs(said.c_str(), stderr);
    if (fba::Task* task = st.task.load()) task->request_stop(fba::Outcome::Interrupted, "interrupted by " + signal_name(sig));
    st.stop.request_stop();  // a constructor waiting on a device gives up
  }
}

void on_unexpected_exit() {
  auto& st = state();
  if (st.returning.load() || st.exit_taken.exchange(true)) return;
  const fba::ActiveCall call = fba::active_call();
  const char* plugin = fba::plugin_being_loaded();
  std::string who = call.component ? std::string("component '") + call.component + "' (" + call.type +
                                         ") called exit() from " + call.call
                    : plugin       ? std::string("the plugin ") + plugin + " called exit() while it was loaded"
                                   : std::string("a plugin called exit() while ") + st.phase.load();
  std::fprintf(stderr, "fba-run: unexpected exit: %s; the run fails\n", who.c_str());
  fba::Task* task = st.task.load();
  if (task && call.component && std::string_view(st.phase.load()) == "running") {
    // On a runtime thread: the main thread stops the run in order (safe states, summary) and
    // leaves with status 3; this thread waits there, reported as not returning from the call.
    task->request_stop(fba::Outcome::RuntimeError, who);
    for (;;) pause();
  }
  const std::string error = write_summary(early_result(fba::Outcome::RuntimeError, "unexpected exit: " + who));
  if (!error.empty()) std::fprintf(stderr, "fba-run: could not write the summary %s\n", error.c_str());
  leave(kRuntimeError);
}

void install_crash_handlers() {
  static char stack[64 * 1024];  // the main thread's; runtime threads get theirs from the library
  stack_t ss{};
  ss.ss_sp = stack;
  ss.ss_size = sizeof stack;
  sigaltstack(&ss, nullptr);
  struct sigaction sa {};
  sa.sa_sigaction = on_crash;
  sa.sa_flags = SA_SIGINFO | SA_ONSTACK;
  sigemptyset(&sa.sa_mask);
  for (int sig : kFaultSignals) sigaction(sig, &sa, nullptr);
}

}  // namespace fba_run
