// Runs the real fba-run binary (or another of the project's programs) from a test: its output to a file, signals, waits that poll
// for a file or a line rather than a clock.
#pragma once

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fcntl.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "support/temp_dir.hpp"
#include "support/build_paths.hpp"

extern char** environ;

namespace fba::test {

namespace fs = std::filesystem;

struct Result {
  int status = -1;  // exit status, or 128 + signal
  std::string output;
};

inline std::string read_file(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A folder of its own for each test (and each call within it), removed when the test ends.
inline fs::path temp_dir(const std::string& name) { return fba::test::TempDir::until_exit(name); }

// The test plugin that misbehaves on request (tests/tasks/misbehaving), never installed.
inline std::string misbehaving_plugins() { return fba::test::binary_dir() + "/tests/tasks/misbehaving/plugins"; }

// Every signal that can be caught and whose default action ends the process (signal(7): Term and
// Core), SIGUSR1 aside (fba-run's live-graph request): each must end a run in order, 128 + N.
inline std::vector<int> terminating_signals() {
  std::vector<int> v{SIGHUP,    SIGINT,  SIGQUIT, SIGILL,  SIGTRAP,   SIGABRT, SIGBUS, SIGFPE,
                     SIGSEGV,   SIGUSR2, SIGPIPE, SIGALRM, SIGTERM,   SIGSTKFLT, SIGXCPU, SIGXFSZ,
                     SIGVTALRM, SIGPROF, SIGIO,   SIGPWR,  SIGSYS};
  for (int sig = SIGRTMIN; sig <= SIGRTMAX; ++sig) v.push_back(sig);
  return v;
}

// A running fba-run, its output going to a file.
class Process {
 public:
  // `signals_blocked`: the terminating signals blocked from exec, as a supervisor can start its
  // child. Before fba-run's first instruction the dynamic loader runs for a few milliseconds,
  // and a signal there ends any program by the default action; fba-run blocks them itself from
  // its first instruction on (.preinit_array), so this only closes the loader's window.
  // `program`: fba-run unless another of the project's programs is tested (fba-inspect).
  explicit Process(std::vector<std::string> args, const std::vector<std::string>& env = {},
                   bool signals_blocked = false, const std::string& program = fba::test::program("fba-run")) {
    log_ = temp_dir("log") / "output.txt";
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    args.insert(args.begin(), program);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    std::vector<std::string> vars = env;
    for (char** e = environ; *e; ++e) vars.emplace_back(*e);
    std::vector<char*> envp;
    for (auto& v : vars) envp.push_back(v.data());
    envp.push_back(nullptr);
    posix_spawnattr_t attr;
    posix_spawnattr_init(&attr);
    if (signals_blocked) {
      sigset_t mask;
      sigemptyset(&mask);
      for (int sig : terminating_signals()) sigaddset(&mask, sig);
      posix_spawnattr_setsigmask(&attr, &mask);
      posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGMASK);
    }
    if (posix_spawn(&pid_, program.c_str(), &actions, &attr, argv.data(), envp.data()) != 0) pid_ = 0;
    posix_spawnattr_destroy(&attr);
    posix_spawn_file_actions_destroy(&actions);
  }
  ~Process() {
    if (pid_ > 0) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  void signal(int sig) const { kill(pid_, sig); }
  bool running() const { return pid_ > 0 && waitpid(pid_, nullptr, WNOHANG | WNOWAIT) == 0; }
  std::string output() const { return read_file(log_); }
  // Waits until the output holds `text` or the process ended; true if it holds it.
  bool wait_for_output(const std::string& text) const {
    for (;;) {
      if (output().find(text) != std::string::npos) return true;
      siginfo_t info{};
      if (waitid(P_PID, pid_, &info, WEXITED | WNOHANG | WNOWAIT) == 0 && info.si_pid == pid_)
        return output().find(text) != std::string::npos;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  }
  // Waits until `file` exists or the process ended; true if it exists.
  bool wait_for_file(const fs::path& file) const {
    for (;;) {
      if (fs::exists(file)) return true;
      siginfo_t info{};
      if (waitid(P_PID, pid_, &info, WEXITED | WNOHANG | WNOWAIT) == 0 && info.si_pid == pid_) return fs::exists(file);
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  }
  Result wait() {
    Result r;
    int status = 0;
    if (pid_ <= 0 || waitpid(pid_, &status, 0) != pid_) return r;
    pid_ = 0;
    r.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    r.output = output();
    return r;
  }

 private:
  pid_t pid_ = 0;
  fs::path log_;
};

// Runs fba-run with arguments to the end.
inline Result fba_run(std::vector<std::string> args, const std::vector<std::string>& env = {}) {
  Process p(std::move(args), env);
  return p.wait();
}

}  // namespace fba::test
