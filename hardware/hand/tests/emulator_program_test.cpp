// fba-robotiq-3f-emulator as a person runs it: it prints its pseudo-terminal, links it where asked,
// and hw.robotiq_3f opens that link as it would /dev/ttyUSB0; scheduled faults reach the driver;
// bad options are refused with the usage.
#include <gtest/gtest.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fba/task.hpp>
#include <fba/testing.hpp>
#include <fstream>
#include <fba/types/grasp.hpp>
#include <fba/types/grasp_execution.hpp>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "support/built_plugins.hpp"
#include "support/child_process.hpp"
#include "support/temp_dir.hpp"
#include "support/build_paths.hpp"

extern char** environ;

using namespace std::chrono_literals;
using fba::testing::ComponentHarness;
using fba::test::Child;

namespace {

fba::Grasp grasp() {
  fba::Grasp g;
  g.aperture = 0.1;
  g.spread = 0.03;
  return g;
}

fba::testing::Params params(const std::string& device) {
  return {{"device", device}, {"response_timeout", 2.0}, {"retries", 1}, {"poll_period", 0.01}, {"hold_time", 0.2}};
}

// Takes a grasp of the emulator's object and expects it held: the driver works on the emulator's line.
void expect_held(ComponentHarness& h) {
  h.push("grasp", grasp());
  ASSERT_EQ(h.run(), 1);
  ASSERT_EQ(h.failure(), "");
  const auto results = h.values<fba::GraspExecution>("result");
  ASSERT_EQ(results.size(), 1u);
  EXPECT_TRUE(results[0].held) << results[0].reason;
}

}  // namespace

TEST(Robotiq3fEmulatorProgram, DriverOnItsLinkHoldsTheObjectAndTheProgramEndsOnSigterm) {
  fba::test::TempDir dir;
  const std::string link = dir.file("hand");
  Child emulator({fba::test::program("fba-robotiq-3f-emulator"), "--link", link, "--activation-s", "0.05", "--object-width", "0.05"});
  ASSERT_NE(emulator.read_until("(link " + link + ")").find("Modbus RTU slave 9 on /dev/pts/"), std::string::npos);
  {
    ComponentHarness h(fba::test::built_plugins(), "hw.robotiq_3f", params(link));
    expect_held(h);
  }
  EXPECT_EQ(emulator.wait(SIGTERM), 0);
  EXPECT_NE(emulator.read_until("stopped").find("Robotiq 3-Finger emulator: stopped"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(std::filesystem::symlink_status(link)));
}

TEST(Robotiq3fEmulatorProgram, ScheduledDisconnectReachesTheDriverAsALineThatIsGone) {
  fba::test::TempDir dir;
  const std::string link = dir.file("hand");
  Child emulator({fba::test::program("fba-robotiq-3f-emulator"), "--link", link, "--activation-s", "0.05", "--disconnect-after", "1"});
  emulator.read_until("(link " + link + ")");
  // Grasps until the line goes (during activation, if this machine is slow enough: the same report).
  std::string report;
  try {
    ComponentHarness h(fba::test::built_plugins(), "hw.robotiq_3f", params(link));
    for (int i = 0; i < 1000 && report.empty(); ++i) {
      h.push("grasp", grasp());
      h.run();
      report = h.failure();
    }
  } catch (const std::exception& e) {
    report = e.what();
  }
  EXPECT_NE(report.find(link), std::string::npos) << report;
  EXPECT_NE(report.find("the serial line is gone"), std::string::npos) << report;
  EXPECT_EQ(emulator.wait(0), 0);
  EXPECT_NE(emulator.read_until("disconnected").find("disconnected (fault injection)"), std::string::npos);
}

TEST(Robotiq3fEmulatorProgram, BadOptionIsRefusedWithTheUsage) {
  Child emulator({fba::test::program("fba-robotiq-3f-emulator"), "--fault-after", "1:ZZ"});
  EXPECT_EQ(emulator.wait(0), 2);
  const std::string out = emulator.read_until("usage:");
  EXPECT_NE(out.find("--fault-after: 'ZZ' is not an integer"), std::string::npos) << out;
  EXPECT_NE(out.find("usage: fba-robotiq-3f-emulator"), std::string::npos) << out;
}

// The emulated profile's way: the driver, given an emulator, starts it when its device is not
// there (no second terminal), from a thread that blocks the terminating signals as fba-run's do,
// and stops it when the driver goes: the program ends on that SIGTERM and takes its link with it.
TEST(Robotiq3fEmulatorProgram, TheDriverStartsItsEmulatorWhenTheDeviceIsNotThereAndStopsItAtTheEnd) {
  fba::test::TempDir dir;
  const std::string link = dir.file("hand");
  sigset_t terminating, before;
  sigemptyset(&terminating);
  sigaddset(&terminating, SIGTERM);
  sigaddset(&terminating, SIGINT);
  pthread_sigmask(SIG_BLOCK, &terminating, &before);
  {
    auto p = params(link);
    p["emulator"] = std::string("fba-robotiq-3f-emulator --activation-s 0.05 --stall-aperture 0.07");
    ComponentHarness h(fba::test::built_plugins(), "hw.robotiq_3f", p);
    EXPECT_TRUE(std::filesystem::is_symlink(link));
    expect_held(h);
  }
  pthread_sigmask(SIG_SETMASK, &before, nullptr);
  // Ended by its SIGTERM (not the SIGKILL 5 s later): it removed its link on the way out.
  EXPECT_FALSE(std::filesystem::exists(std::filesystem::symlink_status(link)));
}

// Never in place of a real device: a device that is there (here a plain file) and does not work is
// the device's failure, and no emulator is started.
TEST(Robotiq3fEmulatorProgram, AnEmulatorIsNeverStartedInPlaceOfADeviceThatIsThere) {
  fba::test::TempDir dir;
  const std::string device = dir.file("ttyUSB0");
  { std::ofstream(device) << ""; }
  auto p = params(device);
  p["emulator"] = std::string("fba-robotiq-3f-emulator");
  try {
    ComponentHarness h(fba::test::built_plugins(), "hw.robotiq_3f", p);
    FAIL() << "started on a plain file";
  } catch (const fba::ConstructionError& e) {
    EXPECT_EQ(e.outcome(), fba::Outcome::RuntimeError) << e.what();
    EXPECT_NE(std::string(e.what()).find(device), std::string::npos) << e.what();
  }
  EXPECT_TRUE(std::filesystem::is_regular_file(device));
}
