// graph-live.dot: the running task's graph (states, queue fills, rates) written into --output-dir
// every --dot-every seconds and on SIGUSR1, a watcher of the Monitor.
#pragma once

#include <chrono>

#include "monitor.hpp"

namespace fba_run {

// Registers the live graph's writer with `monitor`: every `every` (Monitor::kOnRequest: on SIGUSR1
// only), and at the end, with the rates over the whole run, when `every` is a period.
void watch_live_graph(Monitor& monitor, Monitor::Duration every);

}  // namespace fba_run
