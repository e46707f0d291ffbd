// fba-evaluate's command line: every argument is checked as fba-run checks parameters (a value out
// of range, NaN, inverted bounds or an option that would be ignored is refused with exit status 2
// and a message naming it), and negative numbers are values, not options.
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/temp_dir.hpp"

extern char** environ;

namespace {

struct Result {
  int status = -1;  // exit status, or 128 + signal
  std::string output;
};

Result fba_evaluate(std::vector<std::string> args) {
  const fba::test::TempDir dir;
  const std::string log = dir.file("output.log");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  args.insert(args.begin(), FBA_EVALUATE);
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  Result r;
  const int spawned = posix_spawn(&pid, FBA_EVALUATE, &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) {
    ADD_FAILURE() << "cannot start " << FBA_EVALUATE;
    return r;
  }
  int status = 0;
  waitpid(pid, &status, 0);
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  std::stringstream ss;
  ss << std::ifstream(log).rdbuf();
  r.output = ss.str();
  return r;
}

const std::string kBanana = std::string(FBA_SHARED_DATA_DIR) + "/ycb/YcbBanana/model.obj";
const std::string kDinoSet = std::string(FBA_SHARED_DATA_DIR) + "/middlebury-dino/dinoSR_par.txt";

// The run is refused with exit status 2 and a message that contains `says`.
void expect_refused(const std::vector<std::string>& args, const std::string& says) {
  const Result r = fba_evaluate(args);
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find(says), std::string::npos) << "expected \"" << says << "\" in:\n" << r.output;
}

std::vector<std::string> synthetic(std::initializer_list<std::string> extra) {
  std::vector<std::string> a{"synthetic", "--mesh", kBanana};
  a.insert(a.end(), extra);
  return a;
}

std::vector<std::string> model(std::initializer_list<std::string> extra) {
  std::vector<std::string> a{"model", "--model", kBanana};
  a.insert(a.end(), extra);
  return a;
}

TEST(EvaluateCli, SyntheticRefusesViewsOutOfRange) {
  expect_refused(synthetic({"--views", "0"}), "--views must be in [1, 1000]; found 0");
  expect_refused(synthetic({"--views", "-3"}), "--views must be in [1, 1000]; found -3");
}

TEST(EvaluateCli, SyntheticRefusesNaNElevations) {
  expect_refused(synthetic({"--min-elevation", "nan"}), "--min-elevation must be in [-90, 90]; found nan");
  expect_refused(synthetic({"--max-elevation", "nan"}), "--max-elevation must be in");
  expect_refused(synthetic({"--min-elevation", "60", "--max-elevation", "30"}), "--max-elevation must be in [60, 90]; found 30");
}

TEST(EvaluateCli, SyntheticRefusesNegativeThreadsAndDepthsADenseGridCannotHold) {
  expect_refused(synthetic({"--threads", "-1"}), "--threads must be in [0, 256]; found -1");
  expect_refused(synthetic({"--depth", "19"}), "--depth must be in [1, 10]; found 19");
  expect_refused(synthetic({"--depth", "0"}), "--depth must be in [1, 10]; found 0");
  expect_refused(synthetic({"--tolerance", "inf"}), "--tolerance must be in [0, 1000]; found inf");
}

TEST(EvaluateCli, ModelRefusesDepthOutOfRange) {
  expect_refused(model({"--mesh", kBanana, "--depth", "0"}), "--depth must be in [1, 10]; found 0");
  expect_refused(model({"--images", kDinoSet, "--depth", "30"}), "--depth must be in [1, 10]; found 30");
}

TEST(EvaluateCli, ModelRefusesInvertedNaNOrIncompleteBounds) {
  expect_refused(model({"--mesh", kBanana, "--bounds", "0.1", "-0.1", "-0.1", "-0.1", "0.1", "0.1"}),
                 "--bounds: xmin must be below xmax, both finite; found 0.1 and -0.1");
  expect_refused(model({"--mesh", kBanana, "--bounds", "-0.1", "-0.1", "nan", "0.1", "0.1", "0.1"}),
                 "--bounds: zmin must be below zmax, both finite; found nan and 0.1");
  expect_refused(model({"--mesh", kBanana, "--bounds", "-0.1", "-0.1", "-0.1"}), "--bounds needs 6 numbers");
  expect_refused(model({"--images", kDinoSet, "--bounds", "0.1", "0.1", "0.1", "-0.1", "-0.1", "-0.1"}),
                 "--bounds: xmin must be below xmax");
}

TEST(EvaluateCli, ModelRefusesMeshOptionsWithoutAMesh) {
  expect_refused(model({"--images", kDinoSet, "--bounds", "-0.1", "-0.1", "-0.1", "0.1", "0.1", "0.1"}),
                 "--bounds applies to the comparison with a mesh");
  expect_refused(model({"--images", kDinoSet, "--depth", "7"}), "--depth applies to the comparison with a mesh");
}

TEST(EvaluateCli, UnknownOptionsAreRefused) {
  expect_refused(model({"--mesh", kBanana, "--bogus", "1"}), "unrecognised option '--bogus'");
  expect_refused(synthetic({"-x"}), "unrecognised option '-x'");
}

// The banana compared with itself inside a box given with negative corners: a negative number is a
// value of --bounds, and the run succeeds.
TEST(EvaluateCli, NegativeNumbersAreOptionValues) {
  const Result r = fba_evaluate(model({"--mesh", kBanana, "--depth", "4", "--bounds", "-0.2", "-0.2", "-0.2", "0.2", "0.2", "0.2"}));
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("(a) vs"), std::string::npos) << r.output;
  EXPECT_EQ(fba_evaluate({"model", "-h"}).status, 0);
}

}  // namespace
