// The list of runs fba-evaluate grasp --batch reads (its --help says the format): the task, how a
// run's object and pose reach it, the variants and the runs, each checked with its place in the file.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace fba::evaluate::batch {

namespace fs = std::filesystem;

struct RunSpec {
  std::string mesh;  // absolute
  std::string where;  // the mesh's place in the list, file:line:column
  double x = 0, y = 0, yaw = 0;
  std::vector<std::string> set;
};

struct Variant {
  std::string name;
  std::vector<std::string> set;
};

struct BatchList {
  fs::path file;
  fs::path task;
  std::vector<std::string> fba_run_args, pose_set, set;
  double timeout_s = 600;
  std::vector<Variant> variants;
  std::vector<RunSpec> runs;
};

// The most runs (times variants) a batch may have: at a minute a run, 100,000 runs are 70 days on
// one core; beyond it a list is a mistake, and its runs would be allocated before the first started.
constexpr std::uint64_t kMaxBatchRuns = 100'000;

// The list in `file`; throws std::invalid_argument naming the file, line and column of a mistake.
BatchList read_list(const std::string& file);

}  // namespace fba::evaluate::batch
