// The runs of a batch as child processes: each run's fba-run command line, at most N at a time,
// each stopped after the list's timeout, and all stopped in order when the batch is signalled.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <csignal>
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "batch_list.hpp"

namespace fba::evaluate::batch {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// One child run: what to start, and how it ended.
struct Job {
  const RunSpec* run = nullptr;
  const Variant* variant = nullptr;
  std::string object;
  fs::path dir;
  std::string run_id;  // given to fba-run, which writes it into summary.json: an older run's summary is not this run's
  std::vector<std::string> argv;
  std::string setup_error;  // the run could not be started, or was not: why
  pid_t pid = -1;
  Clock::time_point started;
  bool term_sent = false, kill_sent = false;
  int stopped_by = 0;  // the signal that stopped the batch before this run ended (passed on to it if it ran)
  int status = 0;
  double elapsed_s = 0, cpu_s = 0;
};

// Builds the job's command line.
void prepare(Job& job, const BatchList& l, const std::string& fba_run);

// The job's command line as one line of text (command.txt, --dry-run).
std::string command_line(const Job& job);

// The first SIGTERM, SIGINT or SIGHUP to the batch: runs_all then stops its runs, and the table
// is written for those that finished.
extern volatile std::sig_atomic_t stop_signal;

// A signal ignored when the batch started (nohup's SIGHUP) stays ignored.
void catch_stop_signals();

std::string signal_name(int sig);

// Runs the jobs, at most `parallel` at a time; each line of progress on stderr. When the batch is
// signalled, the running jobs get the same signal and kStopGraceS to end, then SIGKILL; the jobs
// not started are not run. Returns with no child left.
void run_all(std::vector<Job>& jobs, int parallel, double timeout_s);

// fba-run beside this program (the build's or the installed bin folder), else on PATH.
std::string default_fba_run();

// Whether `name` (without a '/') is an executable file in a folder of PATH, as posix_spawnp finds it.
bool on_path(const std::string& name);

// A run's folder: "NN-<object>", NN its place in the list from 01.
std::string folder_name(std::size_t index, const std::string& object);

}  // namespace fba::evaluate::batch
