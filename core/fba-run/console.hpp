// fba-run's console: the progress of a run as people read it, on stderr. One line per stage or
// view ("[2.8 s] synthesis: exploration_movement, view 3 of 10"); on a terminal the current line is
// updated in place (its time in the stage, a component busy in a long call: an arm moving), when
// not, a plain line per change and nothing per tick. Log lines go above the progress line (the
// sink from log_sink()), so the two never garble each other.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <spdlog/sinks/sink.h>

#include "fba/task.hpp"
#include "fba/task_config.hpp"

namespace fba_run {

// One component's place in the run as a sample shows it: its stage, and the view it is at when it
// reports one (the result "views") and has a limit (the parameter "max_views").
struct Step {
  std::string component, stage;
  long long view = -1, of = -1;
  bool operator==(const Step&) const = default;
};

// The components that have a stage or a view count in `now`, in the task's order.
std::vector<Step> steps_of(const fba::RunResult& now, const fba::TaskConfig& config);

// "synthesis: exploration_movement, view 3 of 10"
std::string step_text(const Step& step);

class Console {
 public:
  // Writes to `fd`; `terminal`: the progress line is redrawn in place. `config` is read by update()
  // only, so it must outlive the run, not the Console (which the log sink keeps to the end).
  Console(const fba::TaskConfig& config, int fd, bool terminal);

  // The Monitor's watcher: the progress as of `now`.
  void update(const fba::RunResult& now, const fba::RunResult* previous);
  // Runs `write` (which writes whole lines to the same stream) with the progress line cleared, and
  // draws the line again after it.
  template <class F>
  void above(F&& write) {
    std::lock_guard lock(mutex_);
    erase();
    write();
    draw();
  }
  // The run is over: the progress line is cleared for good, so that the outcome takes its place.
  void close();

  // A spdlog sink that writes through `inner` above the progress line.
  static spdlog::sink_ptr log_sink(std::shared_ptr<Console> console, spdlog::sink_ptr inner);

 private:
  // A component in one call for a while, across samples: what an arm's move looks like.
  struct Busy {
    std::uint64_t invocation = 0;
    double since_s = 0;
    bool said = false;  // its plain line was written
  };
  void write(const std::string& text);
  void erase();
  void draw();
  std::string busy_text(const fba::RunResult& now, const fba::RunResult* previous);

  const fba::TaskConfig& config_;
  const int fd_;
  const bool terminal_;
  std::mutex mutex_;
  std::vector<Step> steps_;  // as the last sample showed them
  double step_since_s_ = 0;  // when one last changed (the run's wall time)
  std::string step_line_;    // "[2.8 s] synthesis: grasp_synthesis, view 5 of 10": the step's line
  std::string shown_;        // the progress line as drawn (terminal)
  bool drawn_ = false;       // it is on the screen now
  std::map<std::string, Busy> busy_;
  bool closed_ = false;
};

}  // namespace fba_run
