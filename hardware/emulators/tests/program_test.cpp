// What every emulator program's main shares: ProgramOptions::read, the command line, with the
// options every program takes (--link, --exit-with-parent, --help), the program's own flags and
// valued options, and a mistake ending the program with exit 2, the reason and the usage; and
// run_program, the device run with the stop signals caught and its end or its error reported.
#include <gtest/gtest.h>

#include <signal.h>

#include <cstdlib>
#include <iostream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "fba/emulators/program.hpp"

namespace {

const fba::emulators::ProgramOptions kCli{"fba-test-emulator", "usage: fba-test-emulator [options]\n"};

// argv for `args`, after a program name; the strings live as long as the Argv.
struct Argv {
  explicit Argv(std::vector<std::string> args) : words(std::move(args)) {
    words.insert(words.begin(), "fba-test-emulator");
    for (auto& w : words) pointers.push_back(w.data());
    pointers.push_back(nullptr);
  }
  int argc() const { return static_cast<int>(words.size()); }
  char** argv() { return pointers.data(); }
  std::vector<std::string> words;
  std::vector<char*> pointers;
};

// Reads `args` with one flag (--quiet) and one valued option (--slave), recording what it saw.
struct Reading {
  fba::emulators::CommonOptions common;
  bool quiet = false;
  std::vector<std::pair<std::string, std::string>> values;
};

Reading read(std::vector<std::string> args) {
  Argv a(std::move(args));
  Reading r;
  r.common = kCli.read(a.argc(), a.argv(), {{"--quiet", [&] { r.quiet = true; }}}, [&](const std::string& name, const std::string& v) {
    if (name != "--slave") return false;
    r.values.emplace_back(name, v);
    return true;
  });
  return r;
}

}  // namespace

TEST(EmulatorProgramOptions, NothingGivenLeavesTheDefaults) {
  const Reading r = read({});
  EXPECT_EQ(r.common.link, "");
  EXPECT_FALSE(r.common.exit_with_parent);
  EXPECT_FALSE(r.quiet);
  EXPECT_TRUE(r.values.empty());
}

TEST(EmulatorProgramOptions, TheCommonOptionsFlagsAndValuedOptionsAreReadInAnyOrder) {
  const Reading r = read({"--slave", "9", "--exit-with-parent", "--quiet", "--link", "/tmp/hand", "--slave", "3"});
  EXPECT_EQ(r.common.link, "/tmp/hand");
  EXPECT_TRUE(r.common.exit_with_parent);
  EXPECT_TRUE(r.quiet);
  const std::vector<std::pair<std::string, std::string>> expected{{"--slave", "9"}, {"--slave", "3"}};
  EXPECT_EQ(r.values, expected);
}

TEST(EmulatorProgramOptions, AValueThatLooksLikeAnOptionIsStillTheValue) {
  const Reading r = read({"--link", "--quiet"});
  EXPECT_EQ(r.common.link, "--quiet");
  EXPECT_FALSE(r.quiet);
}

TEST(EmulatorProgramOptionsDeathTest, HelpPrintsTheUsageAndEndsWell) {
  EXPECT_EXIT(read({"--slave", "1", "--help", "--unknown"}), ::testing::ExitedWithCode(0), "");
  EXPECT_EXIT(read({"-h"}), ::testing::ExitedWithCode(0), "");
}

TEST(EmulatorProgramOptionsDeathTest, MistakesEndTheProgramWithTheReasonAndTheUsage) {
  EXPECT_EXIT(read({"--colour", "red"}), ::testing::ExitedWithCode(2),
              "fba-test-emulator: unknown option '--colour'\nusage: fba-test-emulator");
  EXPECT_EXIT(read({"--slave"}), ::testing::ExitedWithCode(2), "'--slave' needs a value or is unknown");
  EXPECT_EXIT(read({"--colour"}), ::testing::ExitedWithCode(2), "'--colour' needs a value or is unknown");
  EXPECT_EXIT(read({""}), ::testing::ExitedWithCode(2), "an empty argument");
}

// In a child process (a death test): run_program catches SIGINT and SIGTERM for good.
TEST(EmulatorProgramRunDeathTest, TheDevicesEndIsPrintedAndTheProgramEndsWell) {
  EXPECT_EXIT(
      {
        testing::internal::CaptureStdout();
        const int status = fba::emulators::run_program(kCli, "Test emulator", [] { return std::string("stopped"); });
        std::cerr << testing::internal::GetCapturedStdout();
        std::exit(status);
      },
      ::testing::ExitedWithCode(0), "^Test emulator: stopped\n$");
}

TEST(EmulatorProgramRunDeathTest, AnErrorEndsTheProgramWithStatus1AndTheProgramsName) {
  EXPECT_EXIT(std::exit(fba::emulators::run_program(kCli, "Test emulator",
                                                    []() -> std::string { throw std::runtime_error("no pseudo-terminal"); })),
              ::testing::ExitedWithCode(1), "^fba-test-emulator: no pseudo-terminal\n$");
}

TEST(EmulatorProgramRunDeathTest, AStopSignalNoLongerEndsTheProcess) {
  EXPECT_EXIT(std::exit(fba::emulators::run_program(kCli, "Test emulator",
                                                    [] {
                                                      ::raise(SIGTERM);
                                                      return std::string(fba::emulators::detail::stop_signal ? "stopped" : "running");
                                                    })),
              ::testing::ExitedWithCode(0), "");
}
