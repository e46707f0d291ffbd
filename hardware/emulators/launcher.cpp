#include "launcher.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <thread>

extern char** environ;

namespace fba::emulators {

namespace {

namespace fs = std::filesystem;

bool executable(const fs::path& p) { return ::access(p.c_str(), X_OK) == 0 && fs::is_regular_file(p); }

std::string status_text(int status) {
  if (WIFEXITED(status)) return "exited with status " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) return std::string("was ended by signal ") + ::strsignal(WTERMSIG(status));
  return "ended";
}

}  // namespace

std::string find_program(const std::string& name) {
  if (name.find('/') != std::string::npos) return executable(name) ? name : "";
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (!ec && executable(self.parent_path() / name)) return (self.parent_path() / name).string();
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "");
  for (std::string dir; std::getline(dirs, dir, ':');)
    if (!dir.empty() && executable(fs::path(dir) / name)) return (fs::path(dir) / name).string();
  return "";
}

bool free_for_emulator(const std::string& path) {
  std::error_code ec;
  const auto s = fs::symlink_status(path, ec);
  return ec || s.type() == fs::file_type::not_found || s.type() == fs::file_type::symlink;
}

LaunchedEmulator::LaunchedEmulator(const std::string& command, const std::string& link, std::stop_token stop,
                                   std::chrono::milliseconds timeout)
    : link_(link) {
  std::vector<std::string> args;
  std::stringstream words(command);
  for (std::string w; words >> w;) args.push_back(w);
  if (args.empty()) throw std::runtime_error("no emulator program given");
  program_ = find_program(args[0]);
  if (program_.empty())
    throw std::runtime_error("the emulator program '" + args[0] +
                             "' is neither beside this program nor on PATH (build it, or give its path)");
  args[0] = program_;
  args.insert(args.end(), {"--link", link, "--exit-with-parent"});
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, 2, 1);  // what it says goes with the driver's log
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  // fba-run blocks the terminating signals (its signal thread takes them): a child would inherit
  // the mask and the dispositions, and then never end on SIGTERM.
  sigset_t none, all;
  sigemptyset(&none);
  sigfillset(&all);
  posix_spawnattr_setsigmask(&attr, &none);
  posix_spawnattr_setsigdefault(&attr, &all);
  posix_spawnattr_setpgroup(&attr, 0);  // its own group: a Ctrl-C at the terminal is fba-run's to handle
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETPGROUP);
  const int rc = ::posix_spawn(&pid_, program_.c_str(), &actions, &attr, argv.data(), environ);
  posix_spawnattr_destroy(&attr);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) {
    pid_ = -1;
    throw std::runtime_error("cannot start " + program_ + ": " + std::strerror(rc));
  }
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    std::error_code ec;
    if (fs::exists(link, ec)) return;  // the link goes to its terminal once the device is there
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) == pid_) {
      pid_ = -1;
      throw std::runtime_error(program_ + " " + status_text(status) + " before its terminal was at " + link);
    }
    if (stop.stop_requested()) {
      stop_child();
      throw std::runtime_error("the task was stopped while " + program_ + " started");
    }
    if (std::chrono::steady_clock::now() >= deadline) {
      stop_child();
      throw std::runtime_error(program_ + " did not put its terminal at " + link + " within " +
                               std::to_string(timeout.count()) + " ms");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

LaunchedEmulator::~LaunchedEmulator() { stop_child(); }

void LaunchedEmulator::stop_child() {
  if (pid_ <= 0) return;
  ::kill(pid_, SIGTERM);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  int status = 0;
  while (::waitpid(pid_, &status, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() >= deadline) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, &status, 0);
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  pid_ = -1;
}

}  // namespace fba::emulators
