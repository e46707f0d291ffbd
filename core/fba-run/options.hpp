// fba-run's command line, parsed and checked into Options before anything else happens.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "fba/task.hpp"
#include "fba/task_config.hpp"
#include "listen_address.hpp"

namespace fba_run {

struct Options {
  std::filesystem::path task_file;
  bool check = false;  // --check: validate only
  bool dot = false;    // --dot: print the graph only
  std::vector<std::string> sets, plugin_dirs;
  std::string output_dir;  // empty: none
  std::string profile;
  bool profile_given = false;  // --profile was given, if empty: refused, not the task's own
  std::vector<std::string> log_levels;  // --log-level: LEVEL or COMPONENT=LEVEL, in the order given
  std::string run_id;  // --run-id, else a random one
  double timeout = 0;
  double stop_grace = fba::RunOptions{}.stop_grace_s;
  double dot_every = 0;
  int threads = 0;
  std::optional<fba::ExecutorKind> executor;
  std::optional<fba::serve::ListenAddress> serve;  // --serve: the live view's address
  bool serve_keep = false;  // --serve-keep: after the run, serve its final state until SIGINT or SIGTERM
  // The first value refused (--timeout, --stop-grace, --threads, --dot-every, --executor, --serve,
  // --serve-keep without --serve), as fba-run says it: refused once the output folder can hold the
  // summary that says so.
  std::string invalid;
};

// "fba-run: MESSAGE" and where to find help, on stderr; returns the configuration error's status.
int usage_error(const std::string& message);

// The command line as Options. Nullopt when fba-run ends here, `status` its exit status: --help,
// --version, or a mistake said on stderr before there is a folder to write a summary into.
std::optional<Options> parse_options(int argc, char** argv, int& status);

}  // namespace fba_run
