// fba-run's run (see run.hpp): options applied, plugins found, the task loaded (--check and --dot
// end there), constructed and run, the last line said and the summary written. Apart from the
// signals and the summary file, which every way out shares; this is the one way through.
#include "run.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include "fba/log.hpp"
#include "fba/message_text.hpp"
#include "fba/registry.hpp"
#include "fba/task.hpp"
#include "console.hpp"
#include "live_graph.hpp"
#include "log_levels.hpp"
#include "live_view.hpp"
#include "monitor.hpp"
#include "outcome_text.hpp"
#include "options.hpp"
#include "run_state.hpp"
#include "signals.hpp"
#include "summary_file.hpp"

namespace fba_run {

namespace {

// How often the running task is sampled for its views; --dot-every's shorter period if given.
constexpr std::chrono::milliseconds kMonitorPeriod{100};

// A mistake on the command line or in the task: said, written into the summary, exit 2.
int refuse(const std::string& message, bool usage = true) {
  if (usage) usage_error(message);
  else std::cerr << message << "\n";
  const std::string error = write_summary(early_result(fba::Outcome::ConfigError, message));
  if (!error.empty()) std::cerr << "fba-run: could not write the summary " << error << "\n";
  return kConfigError;
}

// The output folder first, so that every end from here on writes its summary there, this
// run's (an earlier run's summary is replaced before anything can fail). An exit status when
// fba-run ends here.
std::optional<int> prepare_output_dir(const Options& o, fba::RunOptions& options) {
  auto& st = state();
  std::error_code ec;
  fs::create_directories(o.output_dir, ec);
  if (ec) return usage_error("cannot create --output-dir '" + o.output_dir + "': " + ec.message());
  options.output_dir = fs::absolute(o.output_dir);
  {
    std::lock_guard lock(st.mutex);  // a second signal's summary may be written at any moment
    st.summary = options.output_dir / "summary.json";
    st.live_dot = options.output_dir / "graph-live.dot";
  }
  if (const std::string error = start_summary(); !error.empty()) {
    std::cerr << "fba-run: could not write the summary " << error << "\n";
    return kRuntimeError;
  }
  return std::nullopt;
}

// The plugins found (their manifests read) and the task loaded and checked into `config`. An exit
// status when fba-run ends here.
std::optional<int> load(const Options& o, fba::Registry& registry, fba::TaskConfig& config) {
  std::vector<fs::path> extra(o.plugin_dirs.begin(), o.plugin_dirs.end());
  for (const auto& d : extra)
    if (!fs::is_directory(d)) return refuse("--plugin-path '" + d.string() + "' is not a folder");
  // Reads the plugins' manifests only; a plugin is loaded when the task uses one of its types, so a
  // broken plugin fails only the tasks that need it (load_task says so); here it is a warning.
  for (const auto& e : registry.load_path(fba::plugin_search_path(extra)))
    std::cerr << "fba-run: warning: plugin " << e.file() << ": " << e.reason() << "\n";
  if (int status = 0; interrupted_early(status)) return status;

  fba::LoadOptions load;
  for (const auto& s : o.sets) load.overrides.push_back({s});
  load.profile = o.profile;
  load.profile_given = o.profile_given;  // an empty name is refused, not the default
  try {
    config = fba::load_task(o.task_file, registry, load);
  } catch (const fba::ConfigError& e) {
    std::string reason;
    for (const auto& d : e.diagnostics()) reason += (reason.empty() ? "" : "\n") + d.str();
    return refuse(reason, false);
  } catch (const fba::PluginError& e) {
    return refuse(o.task_file.string() + ": the task needs plugin " + e.file() + ", which cannot be used: " + e.reason(), false);
  }
  return std::nullopt;
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

// What --check prints: the counts, and what a run would use: the task parameters' values, and per
// slot the bound type's interface, which is what must agree between two profiles of one task.
void print_check(const fs::path& task_file, const fba::TaskConfig& config, const fba::Registry& registry) {
  std::cout << task_file.string() << ": ok (" << config.components.size() << " components, " << config.connections.size()
            << " connections, " << config.rules.size() << " event rules)\n";
  for (const auto& p : config.params)
    std::cout << "parameter " << p.name << " = " << fba::to_string(p.value) << "  (" << fba::to_string(p.type) << ", " << p.source
              << ")\n";
  if (!config.profile.empty()) std::cout << "profile " << config.profile << " (" << config.profile_file.string() << ")\n";
  for (const auto& slot : config.slots)
    std::cout << "slot " << slot.name << ": " << slot.type->spec.type_name() << "\n" << fba::describe(fba::interface_of(slot.type->spec));
  if (!config.slots.empty()) compare_profiles(config, registry);
}

// The task's components constructed; null when one refused or failed (said, the summary written,
// `status` the exit status).
std::unique_ptr<fba::Task> construct(const fba::TaskConfig& config, const fba::RunOptions& options, int& status) {
  auto& st = state();
  st.phase.store("constructing");
  try {
    return std::make_unique<fba::Task>(config, options);
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
    return nullptr;
  }
}

// The views of the running task on the Monitor's one thread (the progress, the live graph), started.
void start_monitor(Monitor& monitor, const Options& o, Console& console) {
  auto& st = state();
  monitor.watch([&console](const fba::RunResult& now, const fba::RunResult* previous) { console.update(now, previous); },
                {.every = kMonitorPeriod, .at_end = false});  // not faster with a quick --dot-every
  using Duration = Monitor::Duration;
  const Duration dot_every = o.dot_every > 0 ? std::chrono::duration_cast<Duration>(std::chrono::duration<double>(o.dot_every))
                                             : Monitor::kOnRequest;
  if (!st.live_dot.empty()) watch_live_graph(monitor, dot_every);
  monitor.start(std::min<Duration>(kMonitorPeriod, std::max<Duration>(dot_every, Duration(1))));
  std::lock_guard lock(st.mutex);
  st.monitor.store(&monitor);
}

// The end of a run: where it was and the signal that stopped it noted, the summary written and the
// last line said. Returns the exit status.
int report(fba::RunResult& result) {
  auto& st = state();
  result.phase = st.signal_phase.load() ? st.signal_phase.load() : st.phase.load();
  result.signal = st.signal.load();  // also when the stop it asked for ended in another outcome
  // Stopped while constructing, the runtime names the constructor it cut short; the signal too.
  if (result.signal && result.outcome == fba::Outcome::Interrupted && result.reason.rfind("interrupted by ", 0) != 0)
    result.reason = "interrupted by " + signal_name(result.signal) + ": " + result.reason;
  int status = result.exit_code();
  const std::string error = write_summary(result);
  std::cerr << "fba-run: " << outcome_text(result);
  if (result.lost_to_restarts > 0) {
    std::uint64_t restarts = 0;
    for (const auto& c : result.components) restarts += c.restarts;
    std::cerr << "; " << result.lost_to_restarts << " sample(s) lost to " << restarts << " restart(s)";
  }
  std::cerr << std::endl;
  if (!error.empty()) {
    std::cerr << "fba-run: the run failed: could not write the summary " << error << "\n";
    status = kRuntimeError;
  }
  return status;
}

}  // namespace

int run(int argc, char** argv) {
  auto& st = state();
  int status = 0;
  const std::optional<Options> parsed = parse_options(argc, argv, status);
  if (!parsed) return status;
  const Options& o = *parsed;
  st.config.file = o.task_file;
  st.run_id = o.run_id;
  fba::RunOptions options;
  if (!o.output_dir.empty())
    if (const auto end = prepare_output_dir(o, options)) return *end;
  if (!o.invalid.empty()) return refuse(o.invalid);
  options.executor = o.executor;
  if (const std::string refused = apply_log_levels(o.log_levels, nullptr); !refused.empty()) return refuse(refused);
  if (interrupted_early(status)) return status;

  fba::Registry registry;
  fba::TaskConfig config;
  if (const auto end = load(o, registry, config)) return *end;
  if (const std::string refused = apply_log_levels(o.log_levels, &config); !refused.empty()) return refuse(refused);
  if (o.dot) {
    std::cout << fba::to_dot(config);
    return 0;
  }
  if (o.check) {
    try {
      fba::check_construction(config);  // the filters constructed as a run would, the devices left alone
    } catch (const fba::ConfigError& e) {
      std::string reason;
      for (const auto& d : e.diagnostics()) reason += (reason.empty() ? "" : "\n") + d.str();
      return refuse(reason, false);
    }
    print_check(o.task_file, config, registry);
    return 0;
  }
  {
    std::lock_guard lock(st.mutex);  // the watcher reads it for live dumps
    st.config = config;
  }
  std::optional<LiveView> live;  // --serve's server starts here, so that the page shows the construction too
  try {
    live.emplace(o, config);
  } catch (const std::runtime_error& e) {
    return refuse(std::string("fba-run: ") + e.what(), false);
  }
  if (interrupted_early(status)) return status;
  options.threads = o.threads;
  options.timeout_s = o.timeout;
  options.stop_grace_s = o.stop_grace;
  options.stop = st.stop.get_token();

  // The progress on stderr from the construction on, the log lines above it.
  auto console = std::make_shared<Console>(config, STDERR_FILENO, isatty(STDERR_FILENO) == 1);
  fba::set_log_sink(Console::log_sink(console, fba::log_sink()));
  st.console.store(console.get());  // kept alive by the sink: a signal's message goes above the line
  std::unique_ptr<fba::Task> task = construct(config, options, status);
  if (!task) return status;
  {
    // A signal during construction still stops in order: run() then only takes the safe states.
    std::lock_guard lock(st.mutex);
    st.task.store(task.get());
    if (const int sig = st.signal.load())
      task->request_stop(fba::Outcome::Interrupted, "interrupted by " + signal_name(sig) + " while " + st.signal_phase.load());
    else
      st.phase.store("running");
  }
  // Registered again now: handlers run newest first, so this one runs before the plugins'
  // static destructors, while the components still have what they use.
  std::atexit(on_unexpected_exit);

  Monitor monitor([&task] { return task->snapshot(); });
  live->watch(*task, monitor);
  start_monitor(monitor, o, *console);
  fba::RunResult result = task->run();
  {
    std::lock_guard lock(st.mutex);  // SIGUSR1 asks it no more
    st.monitor.store(nullptr);
  }
  monitor.finish(result);
  console->close();
  live->before_summary();
  status = report(result);
  live->end(result);
  if (!result.stuck.empty() || st.exit_taken.load()) leave(status);  // threads still run in components
  {
    std::lock_guard lock(st.mutex);  // a live dump in progress finishes first
    st.task.store(nullptr);
  }
  task.reset();
  live->keep_serving();  // --serve-keep: until a stop signal; the status stays the run's
  return status;
}

}  // namespace fba_run
