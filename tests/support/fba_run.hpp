// fba-run started from a test (through support/child_process.hpp), and what its tests share: a
// folder per call, the misbehaving test plugin, and what fba-run says refusing a command line.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "support/build_paths.hpp"
#include "support/child_process.hpp"
#include "support/temp_dir.hpp"

namespace fba::test {

namespace fs = std::filesystem;

// A folder of its own for each test (and each call within it), removed when the test process ends.
inline fs::path temp_dir(const std::string& name) { return fba::test::TempDir::until_exit(name); }

// The test plugin that misbehaves on request (tests/tasks/misbehaving), never installed.
inline std::string misbehaving_plugins() { return fba::test::binary_dir() + "/tests/tasks/misbehaving/plugins"; }

// fba-run started with `args`; it runs until it ends or the returned Child goes.
inline std::vector<std::string> fba_run_command(std::vector<std::string> args) {
  args.insert(args.begin(), fba::test::program("fba-run"));
  return args;
}

// Runs fba-run with arguments to the end; `env`: NAME=value added to the environment.
inline Result fba_run(std::vector<std::string> args, std::vector<std::string> env = {}) {
  return run(fba_run_command(std::move(args)), {.env = std::move(env)});
}

// What fba-run says refusing a command line (or its task) with exit status 2; another status is a
// test failure.
inline std::string refusal(std::vector<std::string> args) {
  const Result r = fba_run(std::move(args));
  EXPECT_EQ(r.status, 2) << r.output;
  return r.output;
}

}  // namespace fba::test
