// The programs, as a person runs them: fba-canopen-arm-emulator on a new pseudo-terminal, and the
// master (in this process, or as fba-canopen) opening that terminal as it would /dev/ttyUSB0.
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

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

extern char** environ;

using namespace std::chrono_literals;

namespace {

// A child process with its stdout and stderr on a pipe; killed and reaped when it goes out of scope.
class Child {
 public:
  explicit Child(std::vector<std::string> args) {
    int fds[2];
    if (::pipe(fds) != 0) throw std::runtime_error("pipe failed");
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, fds[1], 1);
    posix_spawn_file_actions_adddup2(&actions, fds[1], 2);
    posix_spawn_file_actions_addclose(&actions, fds[0]);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    const int rc = posix_spawn(&pid_, argv[0], &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    ::close(fds[1]);
    out_ = fds[0];
    if (rc != 0) throw std::runtime_error("cannot start " + args[0]);
  }
  ~Child() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    ::close(out_);
  }
  // Output until `needle` appears or the timeout passes (then whatever came).
  std::string read_until(const std::string& needle, std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (output_.find(needle) == std::string::npos) {
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) break;
      pollfd p{out_, POLLIN, 0};
      if (::poll(&p, 1, static_cast<int>(left.count())) <= 0) break;
      char buffer[512];
      const ssize_t n = ::read(out_, buffer, sizeof buffer);
      if (n <= 0) break;
      output_.append(buffer, static_cast<std::size_t>(n));
    }
    return output_;
  }
  // The exit status after `signal` (0: none sent) once it ends; -1 if it did not end in time.
  int wait(int signal, std::chrono::milliseconds timeout) {
    if (signal) ::kill(pid_, signal);
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        read_until("\x01", 100ms);  // what is left in the pipe
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      if (std::chrono::steady_clock::now() >= deadline) return -1;
      std::this_thread::sleep_for(5ms);
    }
  }

 private:
  pid_t pid_ = -1;
  int out_ = -1;
  std::string output_;
};

// Starts the emulator with `extra` options and returns it with the terminal's path.
std::pair<std::unique_ptr<Child>, std::string> start_emulator(std::vector<std::string> extra = {}) {
  std::vector<std::string> args{FBA_CANOPEN_EMULATOR, "--nodes", "1,2", "--heartbeat-ms", "20"};
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
  Child move({FBA_CANOPEN_TOOL, "--bus", "slcan:" + path, "move", "1", "4000", "400000"});
  EXPECT_EQ(move.wait(0, 30s), 0) << move.read_until("", 0ms);
  EXPECT_NE(move.read_until("", 0ms).find("node 1: at 4000"), std::string::npos) << move.read_until("", 0ms);
  Child read({FBA_CANOPEN_TOOL, "--bus", "slcan:" + path, "read", "1", "2000"});
  EXPECT_EQ(read.wait(0, 30s), 1);
  EXPECT_NE(read.read_until("", 0ms).find("0x06020000 (object does not exist"), std::string::npos)
      << read.read_until("", 0ms);
  Child bad({FBA_CANOPEN_TOOL, "--bus", "slcan:" + path, "read", "200", "1000"});
  EXPECT_EQ(bad.wait(0, 30s), 2);
  EXPECT_NE(bad.read_until("", 0ms).find("node id '200'"), std::string::npos) << bad.read_until("", 0ms);
}
