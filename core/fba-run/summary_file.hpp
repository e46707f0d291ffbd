// summary.json in --output-dir: the placeholder a run starts with, the summary every end writes,
// and the files the run wrote beside it.
#pragma once

#include <filesystem>
#include <string>

#include "fba/task.hpp"

namespace fba_run {

// Replaces whatever summary.json an earlier run left in the output folder, before anything can
// fail, with one that says this run has started: a run that dies without a word (SIGKILL) leaves
// "running", never an older run's outcome. Its time is the mark artefacts_since() compares with.
std::string start_summary();

// Writes summary.json (or `to`); returns the error, or empty.
std::string write_summary(const fba::RunResult& result, std::filesystem::path to = {});

// The run ends before or without Task::run(): a summary with the outcome and where it ended.
fba::RunResult early_result(fba::Outcome outcome, const std::string& reason);

}  // namespace fba_run
