// fba-run's run: the command line's options applied, the plugins found, the task loaded and
// checked, its components constructed and the task run, each end said and written in the summary.
#pragma once

namespace fba_run {

// The whole of fba-run but its signals; returns the exit status.
int run(int argc, char** argv);

}  // namespace fba_run
