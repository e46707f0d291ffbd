// `fba-evaluate grasp <args>` as a user runs it, to its end: its exit status and what it printed;
// and what the batch tests share: stand-ins for fba-run, and what a run's folder says; a test's
// folder with a cube to grasp.
#pragma once

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "fba/geometry/mesh_io.hpp"
#include "support/build_paths.hpp"
#include "support/child_process.hpp"
#include "support/temp_dir.hpp"

namespace fba::test {

// A test with a folder of its own holding cube.ply, a 10 cm cube centred on the origin (a batch
// stands it on the table: on z = 0, its top at 0.1).
class CubeTest : public ::testing::Test {
 protected:
  CubeTest() { geometry::write_ply(geometry::make_box({-0.05, -0.05, -0.05}, {0.05, 0.05, 0.05}), mesh()); }
  std::string mesh() const { return (dir_ / "cube.ply").string(); }
  TempDir tmp_;
  const std::filesystem::path dir_ = tmp_.path();
};

inline Result evaluate_grasp(const std::string& args) {
  return run_shell("'" + program("fba-evaluate") + "' grasp " + args);
}

// A stand-in for fba-run: a shell script that finds its output folder and run id in its arguments
// ($dir and $id, as the batch passes them: -o DIR --run-id ID) and then does `body`.
inline std::filesystem::path write_fba_run_stand_in(const std::filesystem::path& file, const std::string& body) {
  std::ofstream(file) << "#!/bin/sh\n"
                      << "while [ $# -gt 0 ]; do case \"$1\" in -o) dir=$2; shift;; --run-id) id=$2; shift;; esac; shift; done\n"
                      << body << "\n";
  std::filesystem::permissions(file, std::filesystem::perms::owner_all);
  return file;
}

// The --run-id the batch gave the run whose folder is `run_dir` (its command.txt), or "".
inline std::string given_run_id(const std::filesystem::path& run_dir) {
  std::ifstream in(run_dir / "command.txt");
  std::string word;
  while (in >> word)
    if (word == "--run-id" && in >> word) return word;
  return "";
}

// Whether `file` exists within `limit`, looked for every 10 ms (a hang detector, not a speed check).
inline bool wait_for_file(const std::filesystem::path& file, std::chrono::milliseconds limit = std::chrono::seconds(60)) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (!std::filesystem::exists(file)) {
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return true;
}

// The line of `text` that starts with `start`, or "".
inline std::string line_starting(const std::string& text, const std::string& start) {
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);)
    if (line.rfind(start, 0) == 0) return line;
  return "";
}

}  // namespace fba::test
