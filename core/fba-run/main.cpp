// fba-run: loads plugins, checks a task file, and runs it.
#include <signal.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <thread>

#include <boost/program_options.hpp>

#include "fba/log.hpp"
#include "fba/registry.hpp"
#include "fba/task.hpp"
#include "fba/version.hpp"

namespace po = boost::program_options;
namespace fs = std::filesystem;

namespace {

constexpr int kConfigError = 2;

int usage_error(const std::string& message) {
  std::cerr << "fba-run: " << message << "\nTry 'fba-run --help'.\n";
  return kConfigError;
}

}  // namespace

int main(int argc, char** argv) {
  po::options_description visible("Usage: fba-run [options] TASK.yaml\n\nRuns a task. Exit status: 0 success, 1 failure event, "
                                  "2 configuration error, 3 runtime error (also a timeout), 130 interrupted.\n\nOptions");
  std::vector<std::string> sets, plugin_dirs;
  std::string output_dir, executor, log_level = "info";
  double timeout = 0;
  int threads = 0;
  visible.add_options()
      ("help,h", "show this help")
      ("version", "print the version")
      ("check", "check the task and exit (nothing runs)")
      ("dot", "print the task graph as Graphviz DOT and exit")
      ("set,s", po::value(&sets)->composing(), "override a parameter: component.param=value (repeatable)")
      ("plugin-path,p", po::value(&plugin_dirs)->composing(), "add a plugin folder (repeatable; also FBA_PLUGIN_PATH)")
      ("output-dir,o", po::value(&output_dir), "write the run's artefacts (summary.json, images, models) here")
      ("timeout,t", po::value(&timeout), "stop the run after this many seconds (exit 3)")
      ("executor,e", po::value(&executor), "threaded or deterministic (overrides the task file)")
      ("threads", po::value(&threads), "worker threads of the threaded executor (default: one per core)")
      ("log-level", po::value(&log_level), "trace, debug, info, warn, error, critical, off");
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
  if (timeout < 0) return usage_error("--timeout must be >= 0 seconds");
  fba::RunOptions options;
  if (!executor.empty()) {
    if (executor == "threaded") options.executor = fba::ExecutorKind::Threaded;
    else if (executor == "deterministic") options.executor = fba::ExecutorKind::Deterministic;
    else return usage_error("--executor must be threaded or deterministic, not '" + executor + "'");
  }
  try {
    fba::set_log_level(log_level);
  } catch (const std::exception& e) {
    return usage_error(e.what());
  }

  fba::Registry registry;
  std::vector<fs::path> extra(plugin_dirs.begin(), plugin_dirs.end());
  for (const auto& d : extra)
    if (!fs::is_directory(d)) return usage_error("--plugin-path '" + d.string() + "' is not a folder");
  // Reads the plugins' manifests only; a plugin is loaded when the task uses one of its types, so a
  // broken plugin fails only the tasks that need it (load_task says so); here it is a warning.
  for (const auto& e : registry.load_path(fba::plugin_search_path(extra)))
    std::cerr << "fba-run: warning: plugin " << e.file() << ": " << e.reason() << "\n";

  const fs::path task_file = vm["task"].as<std::string>();
  fba::LoadOptions load;
  for (const auto& s : sets) load.overrides.push_back({s});
  fba::TaskConfig config;
  try {
    config = fba::load_task(task_file, registry, load);
  } catch (const fba::ConfigError& e) {
    for (const auto& d : e.diagnostics()) std::cerr << d.str() << "\n";
    return kConfigError;
  } catch (const fba::PluginError& e) {
    std::cerr << task_file.string() << ": the task needs plugin " << e.file() << ", which cannot be used: " << e.reason() << "\n";
    return kConfigError;
  }
  if (vm.count("dot")) {
    std::cout << fba::to_dot(config);
    return 0;
  }
  if (vm.count("check")) {
    std::cout << task_file.string() << ": ok (" << config.components.size() << " components, " << config.connections.size()
              << " connections, " << config.rules.size() << " event rules)\n";
    return 0;
  }
  options.threads = threads;
  options.timeout_s = timeout;
  if (!output_dir.empty()) {
    std::error_code ec;
    fs::create_directories(output_dir, ec);
    if (ec) return usage_error("cannot create --output-dir '" + output_dir + "': " + ec.message());
    options.output_dir = fs::absolute(output_dir);
  }

  // Signals are taken by one thread with sigwait, so the stop is orderly: no work happens in a
  // signal handler. Blocked before any runtime thread exists, so all of them inherit the mask.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  std::unique_ptr<fba::Task> task;
  try {
    task = std::make_unique<fba::Task>(config, options);
  } catch (const fba::ConfigError& e) {
    for (const auto& d : e.diagnostics()) std::cerr << d.str() << "\n";
    return kConfigError;
  }
  std::atomic<bool> done{false};
  std::thread watcher([&] {
    const timespec tick{0, 100'000'000};
    while (!done.load()) {
      siginfo_t info;
      if (sigtimedwait(&signals, &info, &tick) > 0) {
        task->request_stop(fba::Outcome::Interrupted, std::string("interrupted by ") + (info.si_signo == SIGINT ? "SIGINT" : "SIGTERM"));
      }
    }
  });
  fba::RunResult result = task->run();
  done.store(true);
  watcher.join();

  if (!options.output_dir.empty()) {
    std::ofstream out(options.output_dir / "summary.json");
    out << fba::summary_json(result, config);
    if (!out) std::cerr << "fba-run: could not write " << (options.output_dir / "summary.json").string() << "\n";
  }
  std::cerr << "fba-run: " << fba::to_string(result.outcome) << ": " << result.reason;
  if (result.final_event && !result.final_event->payload.empty()) std::cerr << " (" << result.final_event->payload << ")";
  std::fprintf(stderr, " [%.3f s]\n", result.wall_s);
  task.reset();
  return result.exit_code();
}
