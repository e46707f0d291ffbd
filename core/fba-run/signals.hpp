// fba-run's signals: the stop signals taken by one watcher thread, the live graph it writes, the
// forced exit on a second signal, an unexpected exit() and the crash handler.
#pragma once

#include <signal.h>

#include <optional>
#include <string>

#include "fba/task.hpp"

namespace fba_run {

// "SIGHUP", "SIGRTMIN+3": for messages (sigabbrev_np names the classic ones only).
std::string signal_name(int sig);

// The stop signals fba-run takes (those at their default disposition when it starts).
sigset_t taken_signals();

// Sent by main to its own watcher (pthread_kill) when the run is over, so that the watcher need not
// wait out its tick (which every --check would otherwise pay).
constexpr int kWakeSignal = SIGUSR2;

// Leaves without running static destructors or other exit handlers: used when threads were
// left behind in component calls, or an exit() is being handled.
[[noreturn]] void leave(int status);

// A signal that arrived while nothing ran yet ends the run here: exit 128 + signal.
bool interrupted_early(int& status);

// SIGUSR1: the live graph written at once, by the Monitor's thread (see live_graph.hpp); said on
// stderr when there is no --output-dir to write it into.
void request_live_graph();

// The watcher thread: takes the stop signals (a first one stops the run in order, a second forces
// the exit) and SIGUSR1's live graph, until State::watching is cleared.
void watch_signals(sigset_t signals);

// exit() from a plugin (a static constructor, a component): the run fails, with the summary.
void on_unexpected_exit();

// The crash handler for the fault signals, on an alternate stack.
void install_crash_handlers();

}  // namespace fba_run
