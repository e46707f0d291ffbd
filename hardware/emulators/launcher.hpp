// An emulator program started by a driver to play its device, when the device it is configured
// with does not exist or does not answer (the emulated profile: a user needs no second terminal).
// The program runs on a pseudo-terminal linked where the driver looks for its device, in a process
// group of its own (a Ctrl-C at the terminal reaches fba-run, which stops the devices first and the
// emulator after), with the signals fba-run blocks unblocked and at their defaults, and ends with
// the driver (SIGTERM when this object goes, or by itself when its parent has gone).
#pragma once

#include <sys/types.h>

#include <chrono>
#include <stop_token>
#include <string>
#include <vector>

namespace fba::emulators {

class LaunchedEmulator {
 public:
  // Starts `command` (a program and its options, separated by spaces; a program named without a
  // '/' is looked for beside the running program, then on PATH) with `--link LINK
  // --exit-with-parent`, and waits until LINK exists: at most `timeout`, less when `stop` is
  // requested or the program ends first. Throws std::runtime_error naming the program and why.
  LaunchedEmulator(const std::string& command, const std::string& link, std::stop_token stop,
                   std::chrono::milliseconds timeout = std::chrono::seconds(10));
  ~LaunchedEmulator();  // SIGTERM, then SIGKILL if it has not ended within 5 s; reaped
  LaunchedEmulator(const LaunchedEmulator&) = delete;
  LaunchedEmulator& operator=(const LaunchedEmulator&) = delete;

  pid_t pid() const { return pid_; }
  const std::string& program() const { return program_; }  // the path it was started from
  const std::string& link() const { return link_; }

 private:
  void stop_child();

  pid_t pid_ = -1;
  std::string program_, link_;
};

// Whether a driver may put an emulator at `path`: nothing is there, or only a symbolic link (an
// emulator's, alive or left behind); never a real device.
bool free_for_emulator(const std::string& path);

// The program `name` as LaunchedEmulator finds it ("" if nowhere).
std::string find_program(const std::string& name);

}  // namespace fba::emulators
