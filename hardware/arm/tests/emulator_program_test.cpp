// The programs, as a person runs them: fba-canopen-arm-emulator on a new pseudo-terminal, and the
// master (in this process, or as fba-canopen) opening that terminal as it would /dev/ttyUSB0.
#include <signal.h>

#include <chrono>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "fba/can/open_bus.hpp"
#include "fba/canopen/cia402.hpp"
#include "fba/canopen/master.hpp"
#include "support/child_process.hpp"
#include "support/build_paths.hpp"

using namespace std::chrono_literals;

using fba::test::Child;

namespace {

// Starts the emulator with `extra` options and returns it with the terminal's path.
std::pair<std::unique_ptr<Child>, std::string> start_emulator(std::vector<std::string> extra = {}) {
  std::vector<std::string> args{fba::test::program("fba-canopen-arm-emulator"), "--nodes", "1,2", "--heartbeat-ms", "20"};
  args.insert(args.end(), extra.begin(), extra.end());
  auto child = std::make_unique<Child>(args);
  const std::string out = child->read_until("\n", 10s);
  const std::string marker = "SLCAN adapter on ";
  const auto at = out.find(marker);
  if (at == std::string::npos) throw std::runtime_error("the emulator did not say where it is: " + out);
  const auto end = out.find_first_of(" \n", at + marker.size());
  return {std::move(child), out.substr(at + marker.size(), end - at - marker.size())};
}

}  // namespace

TEST(CanopenArmEmulatorProgram, ADriveOnItsTerminalIsEnabledAndMovedThenItStopsOnSigterm) {
  auto [emulator, path] = start_emulator();
  {
    auto bus = fba::can::open_bus("slcan:" + path);
    fba::canopen::Master master(*bus, {.sdo_timeout = 1s});
    master.nmt(fba::canopen::NmtCommand::start, 2);
    fba::canopen::cia402::Drive drive(master, 2);
    drive.enable(2s);
    drive.set_profile(200'000, 2'000'000);
    drive.move_to(12'345, 10s);
    EXPECT_EQ(drive.position(), 12'345);
  }
  EXPECT_EQ(emulator->wait(SIGTERM, 10s), 0);
  EXPECT_NE(emulator->read_until("stopped", 1s).find("CANopen arm emulator: stopped"), std::string::npos);
}

TEST(CanopenArmEmulatorProgram, ScheduledFaultsReachTheMaster) {
  auto [emulator, path] = start_emulator({"--fault-after", "0.2:1:7121", "--silence-after", "0.2:2"});
  auto bus = fba::can::open_bus("slcan:" + path);
  fba::canopen::Master master(*bus, {.sdo_timeout = 1s});
  master.watch_heartbeat(2, 500ms);
  ASSERT_TRUE(master.spin_until([&] { return master.faults().size() >= 2; }, 10s));
  std::string all;
  for (const auto& f : master.faults()) all += f.message + "\n";
  EXPECT_NE(all.find("node 1: EMCY 0x7121 (motor blocked)"), std::string::npos) << all;
  EXPECT_NE(all.find("node 2: heartbeat lost"), std::string::npos) << all;
}

TEST(CanopenArmEmulatorProgram, ADisconnectMidMotionIsABusErrorAndTheEmulatorEnds) {
  auto [emulator, path] = start_emulator({"--disconnect-after", "0.5"});
  auto bus = fba::can::open_bus("slcan:" + path);
  fba::canopen::Master master(*bus, {.sdo_timeout = 1s});
  master.nmt(fba::canopen::NmtCommand::start, 1);
  fba::canopen::cia402::Drive drive(master, 1);
  try {
    drive.enable(2s);
    drive.set_profile(1'000, 10'000);  // 10,000 s to the target: the line goes first
    drive.move_to(10'000'000, 60s);
    FAIL() << "the move outlived the line";
  } catch (const fba::can::BusError& e) {
    EXPECT_NE(std::string(e.what()).find("slcan:" + path), std::string::npos) << e.what();
  }
  EXPECT_EQ(emulator->wait(0, 10s), 0);
  EXPECT_NE(emulator->read_until("disconnected", 1s).find("disconnected (fault injection)"), std::string::npos);
}

TEST(FbaCanopenCommand, MovesADriveAndReportsAnAbortByName) {
  auto [emulator, path] = start_emulator();
  Child move({fba::test::program("fba-canopen"), "--bus", "slcan:" + path, "move", "1", "4000", "400000"});
  EXPECT_EQ(move.wait(0, 30s), 0) << move.read_until("", 0ms);
  EXPECT_NE(move.read_until("", 0ms).find("node 1: at 4000"), std::string::npos) << move.read_until("", 0ms);
  Child read({fba::test::program("fba-canopen"), "--bus", "slcan:" + path, "read", "1", "2000"});
  EXPECT_EQ(read.wait(0, 30s), 1);
  EXPECT_NE(read.read_until("", 0ms).find("0x06020000 (object does not exist"), std::string::npos)
      << read.read_until("", 0ms);
  Child bad({fba::test::program("fba-canopen"), "--bus", "slcan:" + path, "read", "200", "1000"});
  EXPECT_EQ(bad.wait(0, 30s), 2);
  EXPECT_NE(bad.read_until("", 0ms).find("node id '200'"), std::string::npos) << bad.read_until("", 0ms);
}

// A drive left in fault: fba-canopen move refuses it naming its error code and how to reset it;
// reset does, saying which code it had; then the move goes.
TEST(FbaCanopenCommand, MoveRefusesADriveInFaultNamingItsCodeAndResetClearsIt) {
  auto [emulator, path] = start_emulator({"--fault-at-start", "2:7121"});
  Child refused({fba::test::program("fba-canopen"), "--bus", "slcan:" + path, "move", "2", "4000", "400000"});
  EXPECT_EQ(refused.wait(0, 30s), 1) << refused.read_until("", 0ms);
  const std::string why = refused.read_until("", 0ms);
  EXPECT_NE(why.find("node 2: the drive is in fault, error code 0x7121 (motor blocked); 'fba-canopen reset 2' resets it"),
            std::string::npos)
      << why;
  Child reset({fba::test::program("fba-canopen"), "--bus", "slcan:" + path, "reset", "2"});
  EXPECT_EQ(reset.wait(0, 30s), 0) << reset.read_until("", 0ms);
  EXPECT_NE(reset.read_until("", 0ms).find("node 2: fault reset (its error code was 0x7121: motor blocked)"),
            std::string::npos)
      << reset.read_until("", 0ms);
  Child move({fba::test::program("fba-canopen"), "--bus", "slcan:" + path, "move", "2", "4000", "400000"});
  EXPECT_EQ(move.wait(0, 30s), 0) << move.read_until("", 0ms);
  EXPECT_NE(move.read_until("", 0ms).find("node 2: at 4000"), std::string::npos) << move.read_until("", 0ms);
}
