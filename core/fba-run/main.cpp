// fba-run: loads plugins, checks a task file, and runs it.
//
// Every way out ends in order: a signal at any moment (blocked first thing, taken by a watcher
// thread), a plugin calling exit(), a crash (best effort), a component that never returns. Each
// writes summary.json when --output-dir is given and picks the exit status; see
// docs/task-files.md, "Exit statuses and shutdown".
#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <future>
#include <iostream>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <thread>

#include <boost/program_options.hpp>
#include <nlohmann/json.hpp>

#include "fba/message_text.hpp"
#include "fba/log.hpp"
#include "fba/registry.hpp"
#include "fba/task.hpp"
#include "fba/version.hpp"

namespace po = boost::program_options;
namespace fs = std::filesystem;

namespace {

constexpr int kConfigError = 2;
constexpr int kRuntimeError = 3;

int usage_error(const std::string& message) {
  std::cerr << "fba-run: " << message << "\nTry 'fba-run --help'.\n";
  return kConfigError;
}

// "SIGHUP", "SIGRTMIN+3": for messages (sigabbrev_np names the classic ones only).
std::string signal_name(int sig) {
  if (sig >= SIGRTMIN && sig <= SIGRTMAX) return sig == SIGRTMIN ? "SIGRTMIN" : "SIGRTMIN+" + std::to_string(sig - SIGRTMIN);
  const char* abbrev = sigabbrev_np(sig);
  return abbrev ? std::string("SIG") + abbrev : "signal " + std::to_string(sig);
}

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
sigset_t taken_signals() {
  sigset_t set;
  sigemptyset(&set);
  for (int sig : stop_signals())
    if (at_default(sig)) sigaddset(&set, sig);
  return set;
}

// What the watcher, the exit handler and the crash handler need to know about the run.
struct State {
  std::mutex mutex;                           // orders the task's publication against the first signal
  std::atomic<const char*> phase{"loading"};  // loading, constructing, running
  std::atomic<int> signal{0};                 // the first stop signal
  std::atomic<const char*> signal_phase{nullptr};
  std::atomic<int> signals{0};
  std::atomic<fba::Task*> task{nullptr};  // set once constructed
  fs::path summary;                       // empty without --output-dir
  fba::TaskConfig config;                 // what the summary names (the file before it is loaded)
  std::atomic<bool> returning{false};     // main is returning normally: exit() is expected
  std::atomic<bool> exit_taken{false};    // an unexpected exit() is being handled
  std::atomic<bool> watching{true};
  std::thread watcher;
  fs::path live_dot;                // graph-live.dot in --output-dir, written on SIGUSR1 and by --dot-every
  std::atomic<double> dot_every{0};  // seconds between live dumps; 0 for none
  std::stop_source stop;             // the task's RunOptions::stop: reaches constructors too
  std::string run_id;                // summary.json's run_id: which run wrote it
  std::chrono::steady_clock::time_point started = std::chrono::steady_clock::now();
};

// A fault signal sent by kill(2), passed on by the crash handler to the watcher. Plain globals,
// constant-initialised, not members of State: the handler may run before any initialiser has (a
// signal pending since exec arrives when .preinit_array unblocks the faults), and building State
// from there ran libstdc++'s and libfba's code before their own initialisation.
constinit std::atomic<int> g_forwarded{0};
constinit std::atomic<pid_t> g_forwarded_pid{0};
State& state() {
  static State* s = new State;  // alive for the exit handler
  return *s;
}

// The files under the output folder written since summary.json's placeholder (start_summary), by
// path relative to the folder: what this run made, as against what an earlier run left there.
// Bounded: a folder of a million files is not listed whole.
std::vector<std::string> artefacts_since(const fs::path& summary) {
  std::vector<std::string> found;
  std::error_code ec;
  const auto since = fs::last_write_time(summary, ec);
  if (ec) return found;
  const fs::path dir = summary.parent_path();
  for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end && found.size() < 10000; it.increment(ec)) {
    std::error_code e;
    if (!it->is_regular_file(e) || it->path() == summary) continue;
    if (const auto t = it->last_write_time(e); !e && t >= since) found.push_back(fs::relative(it->path(), dir, e).string());
  }
  std::sort(found.begin(), found.end());
  return found;
}

// Replaces whatever summary.json an earlier run left in the output folder, before anything can
// fail, with one that says this run has started: a run that dies without a word (SIGKILL) leaves
// "running", never an older run's outcome. Its time is the mark artefacts_since() compares with.
std::string start_summary() {
  auto& st = state();
  const nlohmann::json j{{"run_id", st.run_id}, {"task_file", st.config.file.string()}, {"outcome", "running"}};
  const std::string text = j.dump(2) + "\n";
  std::FILE* f = std::fopen(st.summary.c_str(), "w");
  if (!f) return st.summary.string() + ": " + std::strerror(errno);
  bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  ok = std::fflush(f) == 0 && ok;
  const int error = errno;
  ok = std::fclose(f) == 0 && ok;
  return ok ? std::string() : st.summary.string() + ": " + std::strerror(error ? error : errno);
}

// Writes summary.json (or `to`); returns the error, or empty.
std::string write_summary(const fba::RunResult& result, fs::path to = {}) {
  auto& st = state();
  if (st.summary.empty()) return {};
  if (to.empty()) to = st.summary;
  fba::RunResult r = result;
  r.run_id = st.run_id;
  r.artefacts = artefacts_since(st.summary);
  const std::string text = fba::summary_json(r, st.config);
  std::FILE* f = std::fopen(to.c_str(), "w");
  if (!f) return to.string() + ": " + std::strerror(errno);
  const bool wrote = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  const int write_errno = errno;
  const bool flushed = std::fflush(f) == 0;
  const int flush_errno = errno;
  const bool closed = std::fclose(f) == 0;
  if (wrote && flushed && closed) return {};
  return to.string() + ": " + std::strerror(!wrote ? write_errno : !flushed ? flush_errno : errno);
}

// The run ends before or without Task::run(): a summary with the outcome and where it ended.
fba::RunResult early_result(fba::Outcome outcome, const std::string& reason) {
  fba::RunResult r;
  r.outcome = outcome;
  r.reason = reason;
  r.phase = state().phase.load();
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - state().started).count();
  if (outcome == fba::Outcome::Interrupted) r.signal = state().signal.load();
  return r;
}

// Leaves without running static destructors or other exit handlers: used when threads were
// left behind in component calls, or an exit() is being handled.
[[noreturn]] void leave(int status) {
  std::fflush(stdout);
  std::fflush(stderr);
  std::cerr.flush();
  _exit(status);
}

// A signal that arrived while nothing ran yet ends the run here: exit 128 + signal.
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

// Writes the live graph (states, queue fills, rates since the previous dump) to graph-live.dot,
// replacing it whole (a viewer never reads half a file). On the watcher thread, and once by main
// after the run (the final state).
void dump_live_graph(std::optional<fba::RunResult>& previous) {
  auto& st = state();
  std::lock_guard lock(st.mutex);  // the task is not destroyed, nor the folder set, while they are read
  if (st.live_dot.empty()) {
    std::fprintf(stderr, "fba-run: SIGUSR1: no --output-dir to write graph-live.dot into\n");
    return;
  }
  fba::Task* task = st.task.load();
  if (!task) return;  // nothing runs yet, or any more
  fba::RunResult now = task->snapshot();
  const std::string text = fba::to_dot(st.config, now, previous ? &*previous : nullptr);
  previous = std::move(now);
  const fs::path partial = st.live_dot.string() + ".partial";
  std::FILE* f = std::fopen(partial.c_str(), "w");
  bool ok = f && std::fwrite(text.data(), 1, text.size(), f) == text.size();
  if (f) ok = std::fclose(f) == 0 && ok;
  if (!ok || std::rename(partial.c_str(), st.live_dot.c_str()) != 0)
    std::fprintf(stderr, "fba-run: could not write %s: %s\n", st.live_dot.c_str(), std::strerror(errno));
}

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

// Sent by main to its own watcher (pthread_kill) when the run is over, so that the watcher need not
// wait out its tick (which every --check would otherwise pay).
constexpr int kWakeSignal = SIGUSR2;

// Whether a signal the watcher took asks for nothing: main's wake-up, or the kernel's notice to a
// writer of this process that its pipe's reader went away (SIGPIPE) or that a file grew past its
// limit (SIGXFSZ), which the write's own error reports where it was made. Each comes from this
// process itself; the same signals sent by another process are stop requests.
bool not_a_request(const siginfo_t& info) {
  const int sig = info.si_signo;
  return info.si_pid == getpid() && (sig == kWakeSignal || sig == SIGPIPE || sig == SIGXFSZ);
}

void watch_signals(sigset_t signals) {
  auto& st = state();
  const timespec tick{0, 50'000'000};
  std::optional<fba::RunResult> previous_dump;
  int first_sig = 0;
  pid_t first_pid = 0;
  std::chrono::steady_clock::time_point first_at;
  auto next_dump = std::chrono::steady_clock::now();
  while (st.watching.load()) {
    if (const double every = st.dot_every.load(); every > 0 && st.task.load() && std::chrono::steady_clock::now() >= next_dump) {
      dump_live_graph(previous_dump);
      next_dump = std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                          std::chrono::duration<double>(every));
    }
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
      dump_live_graph(previous_dump);
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
    std::fprintf(stderr, "fba-run: %s received: stopping in order (a second one forces the exit)\n", signal_name(sig).c_str());
    if (fba::Task* task = st.task.load()) task->request_stop(fba::Outcome::Interrupted, "interrupted by " + signal_name(sig));
    st.stop.request_stop();  // a constructor waiting on a device gives up
  }
}

// exit() from a plugin (a static constructor, a component): the run fails, with the summary.
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

// --check with a profile: the other profiles beside the task, each loaded (without --set) and its
// slots' interfaces compared with this one's. Two profiles fit the task alike when nothing differs.
void compare_profiles(const fba::TaskConfig& config, const fba::Registry& registry) {
  std::vector<fs::path> others;
  std::error_code ec;
  for (fs::directory_iterator it(config.file.parent_path() / "profiles", ec), end; !ec && it != end; it.increment(ec))
    if (it->path().extension() == ".yaml" && !fs::equivalent(it->path(), config.profile_file, ec)) others.push_back(it->path());
  std::sort(others.begin(), others.end());
  for (const auto& other : others) {
    fba::LoadOptions load;
    load.profile = other.string();
    std::cout << "profile " << other.stem().string() << " (" << other.string() << "): ";
    try {
      const fba::TaskConfig alt = fba::load_task(config.file, registry, load);
      std::vector<std::string> diffs;
      for (const auto& slot : config.slots)
        for (const auto& d : fba::interface_differences(fba::slot_interface(config, slot.name), fba::slot_interface(alt, slot.name)))
          diffs.push_back("slot " + slot.name + ": " + d);
      if (diffs.empty()) std::cout << "the same interfaces in every slot\n";
      else std::cout << diffs.size() << " difference(s)\n";
      for (const auto& d : diffs) std::cout << "    " << d << "\n";
    } catch (const fba::ConfigError& e) {
      std::cout << "does not load (" << e.diagnostics().size() << " error(s), the first: " << e.diagnostics().front().str() << ")\n";
    } catch (const std::exception& e) {
      std::cout << "does not load: " << e.what() << "\n";
    }
  }
}

// A number of seconds as written: a value too large for a double (1e400) is infinity, as "inf" is.
bool parse_seconds(const std::string& text, double& out) {
  if (text.empty()) return false;
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size()) return false;
  if (errno == ERANGE && std::abs(v) < 1) return false;  // underflow: not what anyone meant
  out = v;
  return true;
}

std::string random_run_id() {
  std::random_device random;
  char id[17];
  std::snprintf(id, sizeof id, "%08x%08x", random(), random());
  return id;
}

int run(int argc, char** argv) {
  auto& st = state();
  po::options_description visible(
      "Usage: fba-run [options] TASK.yaml\n\nRuns a task. Exit status: 0 success, 1 failure event, 2 configuration "
      "error, "
      "3 runtime error (also a timeout, a component that did not return after the stop, a summary that could not be "
      "written), 128+N interrupted by signal N (130 SIGINT, 143 SIGTERM, 129 SIGHUP, ...).\n\nOptions");
  std::vector<std::string> sets, plugin_dirs;
  std::string output_dir, executor, profile, log_level = "info", timeout_text = "0", stop_grace_text, run_id;
  double timeout = 0;
  double stop_grace = fba::RunOptions{}.stop_grace_s;
  double dot_every = 0;
  int threads = 0;
  visible.add_options()("help,h", "show this help")("version", "print the version")(
      "check", "check the task and exit (nothing runs)")("dot", "print the task graph as Graphviz DOT and exit")(
      "dot-every", po::value(&dot_every),
      "while running, write the live graph (states, queue fills, rates) to OUTPUT-DIR/graph-live.dot every this many "
      "seconds; SIGUSR1 writes it at once")(
      "set,s", po::value(&sets)->composing(),
      "override a parameter: component.param=value, or name=value for a task parameter (repeatable)")(
      "profile", po::value(&profile),
      "bind the task's device slots with this profile: NAME (profiles/NAME.yaml beside the task) or a file")(
      "plugin-path,p", po::value(&plugin_dirs)->composing(), "add a plugin folder (repeatable; also FBA_PLUGIN_PATH)")(
      "output-dir,o", po::value(&output_dir), "write the run's artefacts (summary.json, images, models) here")(
      "run-id", po::value(&run_id),
      "name this run in summary.json (run_id), so a caller can tell its run's summary from an older one (default: a "
      "random id)")(
      "timeout,t", po::value(&timeout_text), "stop the run after this many seconds (exit 3; 0, inf or over 9e9: no limit)")(
      "stop-grace", po::value(&stop_grace_text),
      "seconds that components get to return after a stop, and each actuator's safe state (default 5; inf or over 9e9: "
      "wait for ever)")(
      "executor,e", po::value(&executor), "threaded or deterministic (overrides the task file)")(
      "threads", po::value(&threads), "worker threads of the threaded executor, 0 to 256 (default: the task file's, else one per core)")(
      "log-level", po::value(&log_level), "trace, debug, info, warn, error, critical, off");
  po::options_description hidden;
  hidden.add_options()("task", po::value<std::string>(), "task file");
  po::options_description all;
  all.add(visible).add(hidden);
  po::positional_options_description positional;
  positional.add("task", 1);

  po::variables_map vm;
  try {
    po::store(po::command_line_parser(argc, argv).options(all).positional(positional).run(), vm);
    po::notify(vm);
  } catch (const po::error& e) {
    return usage_error(e.what());
  }
  if (vm.count("help")) {
    std::cout << visible << "\n";
    return 0;
  }
  if (vm.count("version")) {
    std::cout << "fba-run " FBA_VERSION "\n";
    return 0;
  }
  if (!vm.count("task")) return usage_error("no task file given");
  if (vm.count("output-dir") && output_dir.empty()) return usage_error("--output-dir is empty: give a folder");
  const fs::path task_file = vm["task"].as<std::string>();
  st.config.file = task_file;
  st.run_id = run_id.empty() ? random_run_id() : run_id;
  fba::RunOptions options;
  // The output folder first, so that every end from here on writes its summary there, this
  // run's (an earlier run's summary is replaced before anything can fail).
  if (!output_dir.empty()) {
    std::error_code ec;
    fs::create_directories(output_dir, ec);
    if (ec) return usage_error("cannot create --output-dir '" + output_dir + "': " + ec.message());
    options.output_dir = fs::absolute(output_dir);
    {
      std::lock_guard lock(st.mutex);  // a second signal's summary may be written at any moment
      st.summary = options.output_dir / "summary.json";
      st.live_dot = options.output_dir / "graph-live.dot";
    }
    if (const std::string error = start_summary(); !error.empty()) {
      std::cerr << "fba-run: could not write the summary " << error << "\n";
      return kRuntimeError;
    }
  }
  // A mistake on the command line or in the task: said, written into the summary, exit 2.
  auto refuse = [&](const std::string& message, bool usage = true) {
    if (usage) usage_error(message);
    else std::cerr << message << "\n";
    const std::string error = write_summary(early_result(fba::Outcome::ConfigError, message));
    if (!error.empty()) std::cerr << "fba-run: could not write the summary " << error << "\n";
    return kConfigError;
  };
  // NaN compares false with everything: said, not taken as "no limit". Infinity and values beyond
  // the clock's range (1e400 as well as inf) mean no limit (docs/task-files.md, limits).
  if (!parse_seconds(timeout_text, timeout) || !(timeout >= 0))
    return refuse("--timeout must be a number of seconds >= 0 (0: none); found '" + timeout_text + "'");
  if (!stop_grace_text.empty() && (!parse_seconds(stop_grace_text, stop_grace) || !(stop_grace >= 0)))
    return refuse("--stop-grace must be a number of seconds >= 0; found '" + stop_grace_text + "'");
  if (threads < 0 || threads > fba::kMaxThreads)
    return refuse("--threads must be in [0, " + std::to_string(fba::kMaxThreads) + "] (0: the task file's, else one per core); found " +
                       std::to_string(threads));
  if (!(dot_every >= 0 && dot_every <= 1e6)) return refuse("--dot-every must be between 0 and 1e6 seconds");
  if (dot_every > 0 && output_dir.empty()) return refuse("--dot-every needs --output-dir (graph-live.dot is written there)");
  if (!executor.empty()) {
    if (executor == "threaded") options.executor = fba::ExecutorKind::Threaded;
    else if (executor == "deterministic") options.executor = fba::ExecutorKind::Deterministic;
    else return refuse("--executor must be threaded or deterministic, not '" + executor + "'");
  }
  try {
    fba::set_log_level(log_level);
  } catch (const std::exception& e) {
    return refuse(e.what());
  }
  int status = 0;
  if (interrupted_early(status)) return status;

  fba::Registry registry;
  std::vector<fs::path> extra(plugin_dirs.begin(), plugin_dirs.end());
  for (const auto& d : extra)
    if (!fs::is_directory(d)) return refuse("--plugin-path '" + d.string() + "' is not a folder");
  // Reads the plugins' manifests only; a plugin is loaded when the task uses one of its types, so a
  // broken plugin fails only the tasks that need it (load_task says so); here it is a warning.
  for (const auto& e : registry.load_path(fba::plugin_search_path(extra)))
    std::cerr << "fba-run: warning: plugin " << e.file() << ": " << e.reason() << "\n";
  if (interrupted_early(status)) return status;

  fba::LoadOptions load;
  for (const auto& s : sets) load.overrides.push_back({s});
  load.profile = profile;
  load.profile_given = vm.count("profile") > 0;  // an empty name is refused, not the default
  fba::TaskConfig config;
  try {
    config = fba::load_task(task_file, registry, load);
  } catch (const fba::ConfigError& e) {
    std::string reason;
    for (const auto& d : e.diagnostics()) reason += (reason.empty() ? "" : "\n") + d.str();
    return refuse(reason, false);
  } catch (const fba::PluginError& e) {
    return refuse(task_file.string() + ": the task needs plugin " + e.file() + ", which cannot be used: " + e.reason(), false);
  }
  if (vm.count("dot")) {
    std::cout << fba::to_dot(config);
    return 0;
  }
  if (vm.count("check")) {
    std::cout << task_file.string() << ": ok (" << config.components.size() << " components, " << config.connections.size()
              << " connections, " << config.rules.size() << " event rules)\n";
    // What a run would use: the task parameters' values, and per slot the bound type's interface,
    // which is what must agree between two profiles of one task.
    for (const auto& p : config.params)
      std::cout << "parameter " << p.name << " = " << fba::to_string(p.value) << "  (" << fba::to_string(p.type) << ", " << p.source
                << ")\n";
    if (!config.profile.empty()) std::cout << "profile " << config.profile << " (" << config.profile_file.string() << ")\n";
    for (const auto& slot : config.slots)
      std::cout << "slot " << slot.name << ": " << slot.type->spec.type_name() << "\n" << fba::describe(fba::interface_of(slot.type->spec));
    if (!config.slots.empty()) compare_profiles(config, registry);
    return 0;
  }
  {
    std::lock_guard lock(st.mutex);  // the watcher reads it for live dumps
    st.config = config;
  }
  if (interrupted_early(status)) return status;
  options.threads = threads;
  options.timeout_s = timeout;
  options.stop_grace_s = stop_grace;
  options.stop = st.stop.get_token();

  st.phase.store("constructing");
  std::unique_ptr<fba::Task> task;
  try {
    task = std::make_unique<fba::Task>(config, options);
  } catch (const fba::ConfigError& e) {
    std::string reason;
    for (const auto& d : e.diagnostics()) {
      std::cerr << d.str() << "\n";
      reason += (reason.empty() ? "" : "; ") + d.str();
    }
    const auto* construction = dynamic_cast<const fba::ConstructionError*>(&e);
    // A device that failed to start is a runtime error (exit 3); the task's own mistakes exit 2.
    fba::RunResult r = early_result(construction ? construction->outcome() : fba::Outcome::ConfigError, reason);
    if (const int sig = st.signal.load()) {  // the user's stop is what a calling script must see
      r = early_result(fba::Outcome::Interrupted, "interrupted by " + signal_name(sig) + " while constructing; " + reason);
      r.phase = st.signal_phase.load();
    }
    status = r.exit_code();
    if (construction) r.safe_states = construction->safe_states();
    const std::string error = write_summary(r);
    if (!error.empty()) std::cerr << "fba-run: could not write the summary " << error << "\n";
    return status;
  }
  {
    // A signal during construction still stops in order: run() then only takes the safe states.
    std::lock_guard lock(st.mutex);
    st.task.store(task.get());
    if (const int sig = st.signal.load())
      task->request_stop(fba::Outcome::Interrupted, "interrupted by " + signal_name(sig) + " while " + st.signal_phase.load());
    else
      st.phase.store("running");
  }
  st.dot_every.store(dot_every);
  // Registered again now: handlers run newest first, so this one runs before the plugins'
  // static destructors, while the components still have what they use.
  std::atexit(on_unexpected_exit);

  fba::RunResult result = task->run();
  if (dot_every > 0) {
    std::optional<fba::RunResult> none;  // the last dump: rates over the whole run
    dump_live_graph(none);
  }
  result.phase = st.signal_phase.load() ? st.signal_phase.load() : st.phase.load();
  result.signal = st.signal.load();  // also when the stop it asked for ended in another outcome
  // Stopped while constructing, the runtime names the constructor it cut short; the signal too.
  if (result.signal && result.outcome == fba::Outcome::Interrupted && result.reason.rfind("interrupted by ", 0) != 0)
    result.reason = "interrupted by " + signal_name(result.signal) + ": " + result.reason;
  status = result.exit_code();
  const std::string error = write_summary(result);
  std::cerr << "fba-run: " << fba::to_string(result.outcome) << ": " << fba::escape_controls(result.reason);
  if (result.final_event && !result.final_event->payload.empty())
    std::cerr << " (" << fba::escape_controls(result.final_event->payload) << ")";
  if (result.lost_to_restarts > 0) {
    std::uint64_t restarts = 0;
    for (const auto& c : result.components) restarts += c.restarts;
    std::cerr << "; " << result.lost_to_restarts << " sample(s) lost to " << restarts << " restart(s)";
  }
  std::fprintf(stderr, " [%.3f s]\n", result.wall_s);
  if (!error.empty()) {
    std::cerr << "fba-run: the run failed: could not write the summary " << error << "\n";
    status = kRuntimeError;
  }
  if (!result.stuck.empty() || st.exit_taken.load()) leave(status);  // threads still run in components
  {
    std::lock_guard lock(st.mutex);  // a live dump in progress finishes first
    st.task.store(nullptr);
  }
  task.reset();
  return status;
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

int main(int argc, char** argv) {
  // First thing, before any plugin or thread exists: the stop signals are taken by one thread
  // with sigtimedwait (every thread inherits the mask), so a signal at any moment stops the run
  // in order; no work happens in a signal handler. Those blocked already (by .preinit_array) keep their default disposition, so this is the same set.
  sigset_t signals = taken_signals();
  sigaddset(&signals, kWakeSignal);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  install_crash_handlers();  // again: a sanitizer's runtime may have put its own in since
  std::atexit(on_unexpected_exit);
  auto& st = state();
  st.watcher = std::thread(watch_signals, signals);

  const int status = run(argc, argv);
  st.returning.store(true);
  st.watching.store(false);
  pthread_kill(st.watcher.native_handle(), kWakeSignal);
  st.watcher.join();
  if (st.exit_taken.load()) leave(kRuntimeError);
  return status;
}
