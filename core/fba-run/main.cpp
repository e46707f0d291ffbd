// fba-run: loads plugins, checks a task file, and runs it.
//
// Every way out ends in order: a signal at any moment (blocked first thing, taken by a watcher
// thread), a plugin calling exit(), a crash (best effort), a component that never returns. Each
// writes summary.json when --output-dir is given and picks the exit status; see
// docs/task-files.md, "Exit statuses and shutdown". The pieces: options.cpp (the command line),
// run.cpp (loading, constructing, running), summary_file.cpp (summary.json), signals.cpp (the
// watcher, the crash handler, the forced exit).
#include <signal.h>

#include <cstdlib>
#include <thread>

#include "run.hpp"
#include "run_state.hpp"
#include "signals.hpp"

int main(int argc, char** argv) {
  using namespace fba_run;
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
