// graph-live.dot (see live_graph.hpp), replaced whole each time: a viewer never reads half a file.
#include "live_graph.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>

#include "console.hpp"
#include "run_state.hpp"

namespace fba_run {

namespace {

// On the monitor's thread. The task's configuration and the folder are set before the monitor
// starts and not changed while it runs.
void write_live_graph(const fba::RunResult& now, const fba::RunResult* previous) {
  const auto& st = state();
  const std::string text = fba::to_dot(st.config, now, previous);
  const fs::path partial = st.live_dot.string() + ".partial";
  std::FILE* f = std::fopen(partial.c_str(), "w");
  bool ok = f && std::fwrite(text.data(), 1, text.size(), f) == text.size();
  if (f) ok = std::fclose(f) == 0 && ok;
  if (ok && std::rename(partial.c_str(), st.live_dot.c_str()) == 0) return;
  const int error = errno;
  const std::string said = "fba-run: could not write " + st.live_dot.string() + ": " + std::strerror(error) + "\n";
  if (Console* console = st.console.load()) console->above([&] { std::fputs(said.c_str(), stderr); });  // not onto the progress line
  else std::fputs(said.c_str(), stderr);
}

}  // namespace

void watch_live_graph(Monitor& monitor, Monitor::Duration every) {
  monitor.watch(write_live_graph, {.every = every, .at_end = every != Monitor::kOnRequest});
}

}  // namespace fba_run
