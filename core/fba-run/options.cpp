// fba-run's command line (see options.hpp): Boost.Program_options reads it, and each value is
// checked here. Apart from the run so that what fba-run accepts is read in one place.
#include "options.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <random>

#include <boost/program_options.hpp>

#include "fba/version.hpp"
#include "run_state.hpp"

namespace po = boost::program_options;

namespace fba_run {

namespace {

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

// The first value refused, as fba-run says it; empty when every one is valid. Fills in what each means.
std::string refusal(Options& o, const std::string& timeout_text, const std::string& stop_grace_text, const std::string& executor,
                    const std::optional<std::string>& serve) {
  // NaN compares false with everything: said, not taken as "no limit". Infinity and values beyond
  // the clock's range (1e400 as well as inf) mean no limit (docs/task-files.md, limits).
  if (!parse_seconds(timeout_text, o.timeout) || !(o.timeout >= 0))
    return "--timeout must be a number of seconds >= 0 (0: none); found '" + timeout_text + "'";
  if (!stop_grace_text.empty() && (!parse_seconds(stop_grace_text, o.stop_grace) || !(o.stop_grace >= 0)))
    return "--stop-grace must be a number of seconds >= 0; found '" + stop_grace_text + "'";
  if (o.threads < 0 || o.threads > fba::kMaxThreads)
    return "--threads must be in [0, " + std::to_string(fba::kMaxThreads) + "] (0: the task file's, else one per core); found " +
           std::to_string(o.threads);
  if (!(o.dot_every >= 0 && o.dot_every <= 1e6)) return "--dot-every must be between 0 and 1e6 seconds";
  if (o.dot_every > 0 && o.output_dir.empty()) return "--dot-every needs --output-dir (graph-live.dot is written there)";
  if (!executor.empty()) {
    if (executor == "threaded") o.executor = fba::ExecutorKind::Threaded;
    else if (executor == "deterministic") o.executor = fba::ExecutorKind::Deterministic;
    else return "--executor must be threaded or deterministic, not '" + executor + "'";
  }
  if (serve) try {
      o.serve = fba::serve::parse_listen_address(*serve);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
  if (o.serve_keep && !serve) return "--serve-keep needs --serve [ADDR:]PORT: it keeps the live view's server after the run";
  return {};
}

}  // namespace

int usage_error(const std::string& message) {
  std::cerr << "fba-run: " << message << "\nTry 'fba-run --help'.\n";
  return kConfigError;
}

std::optional<Options> parse_options(int argc, char** argv, int& status) {
  Options o;
  po::options_description visible(
      "Usage: fba-run [options] TASK.yaml\n\nRuns a task. Exit status: 0 success, 1 failure event, 2 configuration "
      "error, "
      "3 runtime error (also a timeout, a component that did not return after the stop, a summary that could not be "
      "written), 128+N interrupted by signal N (130 SIGINT, 143 SIGTERM, 129 SIGHUP, ...).\n\nOptions");
  std::string executor, timeout_text = "0", stop_grace_text;
  visible.add_options()("help,h", "show this help")("version", "print the version")(
      "check", "check the task and exit (nothing runs)")("dot", "print the task graph as Graphviz DOT and exit")(
      "dot-every", po::value(&o.dot_every),
      "while running, write the live graph (states, queue fills, rates) to OUTPUT-DIR/graph-live.dot every this many "
      "seconds; SIGUSR1 writes it at once")(
      "set,s", po::value(&o.sets)->composing(),
      "override a parameter: component.param=value, or name=value for a task parameter (repeatable)")(
      "profile", po::value(&o.profile),
      "bind the task's device slots with this profile: NAME (profiles/NAME.yaml beside the task) or a file")(
      "plugin-path,p", po::value(&o.plugin_dirs)->composing(), "add a plugin folder (repeatable; also FBA_PLUGIN_PATH)")(
      "output-dir,o", po::value(&o.output_dir), "write the run's artefacts (summary.json, images, models) here")(
      "run-id", po::value(&o.run_id),
      "name this run in summary.json (run_id), so a caller can tell its run's summary from an older one (default: a "
      "random id)")(
      "timeout,t", po::value(&timeout_text), "stop the run after this many seconds (exit 3; 0, inf or over 9e9: no limit)")(
      "stop-grace", po::value(&stop_grace_text),
      "seconds that components get to return after a stop, and each actuator's safe state (default 5; inf or over 9e9: "
      "wait for ever)")(
      "executor,e", po::value(&executor), "threaded or deterministic (overrides the task file)")(
      "serve", po::value<std::string>(),
      "serve the run's live view (docs/live-view.md) at [ADDR:]PORT: 127.0.0.1 unless ADDR is given, PORT 0 for a free "
      "one; the page's address, with its token, is said on stderr")(
      "serve-keep",
      "with --serve: once the run is over, keep serving its final state (the page, and the run's data to every page "
      "that connects) until SIGINT or SIGTERM; the exit status stays the run's. Without it fba-run exits when the run "
      "ends, as a script expects; a run stopped by a signal exits then too")(
      "threads", po::value(&o.threads), "worker threads of the threaded executor, 0 to 256 (default: the task file's, else one per core)")(
      "log-level", po::value(&o.log_levels)->composing(),
      "LEVEL for every component and fba-run itself, or COMPONENT=LEVEL for one component of the task (a composite "
      "instance: the components inside it); LEVEL is trace, debug, info (the default), warn, error, critical or off "
      "(repeatable: --log-level warn --log-level carver=debug)");
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
    status = usage_error(e.what());
    return std::nullopt;
  }
  status = 0;
  if (vm.count("help")) {
    std::cout << visible << "\n";
    return std::nullopt;
  }
  if (vm.count("version")) {
    std::cout << "fba-run " FBA_VERSION "\n";
    return std::nullopt;
  }
  if (!vm.count("task")) {
    status = usage_error("no task file given");
    return std::nullopt;
  }
  if (vm.count("output-dir") && o.output_dir.empty()) {
    status = usage_error("--output-dir is empty: give a folder");
    return std::nullopt;
  }
  o.task_file = vm["task"].as<std::string>();
  o.check = vm.count("check") > 0;
  o.dot = vm.count("dot") > 0;
  o.profile_given = vm.count("profile") > 0;  // an empty name is refused, not the default
  o.serve_keep = vm.count("serve-keep") > 0;
  if (o.run_id.empty()) o.run_id = random_run_id();
  const std::optional<std::string> serve = vm.count("serve") ? std::optional(vm["serve"].as<std::string>()) : std::nullopt;
  o.invalid = refusal(o, timeout_text, stop_grace_text, executor, serve);
  return o;
}

}  // namespace fba_run
