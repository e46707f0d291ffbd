// The one way a test runs another process: a program (fba-run, fba-evaluate, an emulator,
// fba-lift-test, fba-canopen, a shell command) with its arguments and environment, its output
// captured (or on a pseudo-terminal, for what a program does on a terminal), signalled, waited for;
// or a function of the test run in a forked child, where it may crash or exhaust a limit without
// taking the test down.
//
// The output goes to a file, not a pipe: a program that prints more than a pipe holds never blocks
// on a test that is not reading, and a grandchild that keeps the output open (an emulator fba-run
// started) does not hold a reader up after the child has ended. On a terminal, a thread copies what
// the program writes to that file. Waits poll that file and the child's state; their bounds detect
// a hang, they are no speed check.
#pragma once

#include <poll.h>
#include <pty.h>
#include <signal.h>
#include <spawn.h>
#include <termios.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fcntl.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <stop_token>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <atomic>
#include <utility>
#include <vector>

extern char** environ;

namespace fba::test {

// How a child is started.
struct ChildOptions {
  std::vector<std::string> env;  // NAME=value, ahead of the test's own environment (so they win)
  // The terminating signals (terminating_signals()) blocked from exec, as a supervisor can start
  // its child: before a program's first instruction the dynamic loader runs for a few milliseconds,
  // and a signal there ends any program by the default action.
  bool signals_blocked = false;
  bool stderr_apart = false;  // stderr to err() alone; otherwise stdout and stderr both go to output()
  // stdout and stderr to this descriptor (a pipe the test holds) instead of output(); the test
  // closes its own copy once the child has started.
  int output_fd = -1;
  // stdout and stderr on a pseudo-terminal of 200 columns in raw mode (isatty() is true in the
  // child, and what it writes arrives unchanged: "\n" stays "\n"), copied to output().
  bool terminal = false;
};

// How a child ended, and what it printed.
struct Result {
  int status = -1;     // the exit status, or 128 + N when signal N ended it
  int signal = 0;      // the signal that ended it; 0 if it exited
  std::string output;  // stdout, and stderr unless ChildOptions::stderr_apart
  std::string err;     // stderr, with ChildOptions::stderr_apart
};

inline constexpr std::chrono::milliseconds kNoLimit = std::chrono::milliseconds::max();

// Every signal that can be caught and whose default action ends the process (signal(7): Term and
// Core), SIGUSR1 aside (fba-run's live-graph request): each must end a run in order, 128 + N.
inline std::vector<int> terminating_signals() {
  std::vector<int> v{SIGHUP,    SIGINT,  SIGQUIT, SIGILL,  SIGTRAP,   SIGABRT, SIGBUS, SIGFPE,
                     SIGSEGV,   SIGUSR2, SIGPIPE, SIGALRM, SIGTERM,   SIGSTKFLT, SIGXCPU, SIGXFSZ,
                     SIGVTALRM, SIGPROF, SIGIO,   SIGPWR,  SIGSYS};
  for (int sig = SIGRTMIN; sig <= SIGRTMAX; ++sig) v.push_back(sig);
  return v;
}

inline std::string read_file(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A running program; killed and reaped when it goes out of scope.
class Child {
 public:
  // args[0] is the program's path; throws when it cannot be started.
  explicit Child(std::vector<std::string> args, ChildOptions options = {})
      : dir_(make_output_dir()), out_(dir_ / "output.txt") {
    if (args.empty()) throw std::invalid_argument("Child: no program given");
    if (options.stderr_apart) err_ = dir_ / "stderr.txt";
    int terminal = -1, terminal_end = -1;  // the pseudo-terminal's master and slave
    if (options.terminal) {
      termios raw{};
      cfmakeraw(&raw);
      winsize size{};
      size.ws_col = 200;
      size.ws_row = 50;
      if (::openpty(&terminal, &terminal_end, nullptr, &raw, &size) != 0)
        throw std::runtime_error(std::string("openpty failed: ") + std::strerror(errno));
      ::fcntl(terminal, F_SETFD, FD_CLOEXEC);
      ::fcntl(terminal_end, F_SETFD, FD_CLOEXEC);
    }
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    if (terminal_end >= 0)
      posix_spawn_file_actions_adddup2(&actions, terminal_end, 1);
    else if (options.output_fd >= 0)
      posix_spawn_file_actions_adddup2(&actions, options.output_fd, 1);
    else
      posix_spawn_file_actions_addopen(&actions, 1, out_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (err_.empty())
      posix_spawn_file_actions_adddup2(&actions, 1, 2);
    else
      posix_spawn_file_actions_addopen(&actions, 2, err_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    std::vector<std::string> vars = std::move(options.env);
    for (char** e = environ; *e; ++e) vars.emplace_back(*e);
    std::vector<char*> envp;
    for (auto& v : vars) envp.push_back(v.data());
    envp.push_back(nullptr);
    posix_spawnattr_t attr;
    posix_spawnattr_init(&attr);
    if (options.signals_blocked) {
      sigset_t mask;
      sigemptyset(&mask);
      for (int sig : terminating_signals()) sigaddset(&mask, sig);
      posix_spawnattr_setsigmask(&attr, &mask);
      posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGMASK);
    }
    const int rc = posix_spawn(&pid_, args[0].c_str(), &actions, &attr, argv.data(), envp.data());
    posix_spawnattr_destroy(&attr);
    posix_spawn_file_actions_destroy(&actions);
    if (terminal_end >= 0) ::close(terminal_end);
    if (rc != 0) {
      pid_ = -1;
      if (terminal >= 0) ::close(terminal);
      throw std::runtime_error("cannot start " + args[0] + ": " + std::strerror(rc));
    }
    if (terminal >= 0) {
      drained_ = false;
      copier_ = std::jthread([this, terminal](std::stop_token stop) { copy_terminal(terminal, stop); });
    }
  }
  ~Child() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    if (copier_.joinable()) {
      copier_.request_stop();
      copier_.join();
    }
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  void signal(int sig) const {
    if (pid_ > 0) ::kill(pid_, sig);
  }
  // Whether it has not ended yet (it stays a zombie until a wait reaps it).
  bool running() const {
    if (pid_ <= 0) return false;
    siginfo_t info{};
    return ::waitid(P_PID, pid_, &info, WEXITED | WNOHANG | WNOWAIT) == 0 && info.si_pid != pid_;
  }
  std::string output() const { return read_file(out_); }
  std::string err() const { return err_.empty() ? std::string() : read_file(err_); }

  // Waits until output() holds `text`, the child ended or `limit` passed; true if it holds it.
  bool wait_for_output(const std::string& text, std::chrono::milliseconds limit = kNoLimit) const {
    return poll_until([&] { return output().find(text) != std::string::npos; }, limit);
  }
  // The same on stderr, with ChildOptions::stderr_apart.
  bool wait_for_err(const std::string& text, std::chrono::milliseconds limit = kNoLimit) const {
    return poll_until([&] { return err().find(text) != std::string::npos; }, limit);
  }
  // Waits until `file` exists, the child ended or `limit` passed; true if it exists.
  bool wait_for_file(const std::filesystem::path& file, std::chrono::milliseconds limit = kNoLimit) const {
    return poll_until([&] { return std::filesystem::exists(file); }, limit);
  }
  // The whole line that holds `needle`, without its newline, once it has all come; empty if the
  // child ends or `limit` passes first (a line written in pieces is waited for whole).
  std::string read_line_with(const std::string& needle, std::chrono::milliseconds limit = std::chrono::seconds(60)) const {
    std::string line;
    poll_until([&] {
      const std::string out = output();
      const auto at = out.find(needle);
      const auto end = at == std::string::npos ? at : out.find('\n', at);
      if (end == std::string::npos) return false;
      const auto start = out.rfind('\n', at);
      const std::size_t from = start == std::string::npos ? 0 : start + 1;
      line = out.substr(from, end - from);
      return true;
    }, limit);
    return line;
  }
  // The output once it holds `needle`, the child ended, or `limit` passed.
  std::string read_until(const std::string& needle, std::chrono::milliseconds limit = std::chrono::seconds(60)) const {
    wait_for_output(needle, limit);
    return output();
  }

  // Sends `sig` (0: none) and returns the exit status (128 + N for signal N) once the child ends;
  // -1 if it did not end within `limit`.
  int wait(int sig, std::chrono::milliseconds limit = std::chrono::seconds(60)) {
    if (sig) signal(sig);
    poll_until([] { return false; }, limit);
    if (running()) return -1;
    return reap().status;
  }
  // Waits for the child to end, without a bound of its own; its status and output.
  Result wait() { return reap(); }

 private:
  // Polls `done` until it holds or the child has ended (then once more) or `limit` has passed.
  template <typename Done>
  bool poll_until(Done done, std::chrono::milliseconds limit) const {
    const auto start = std::chrono::steady_clock::now();
    for (;;) {
      if (done()) return true;
      if (!running() && drained_) return done();
      if (limit != kNoLimit && std::chrono::steady_clock::now() - start >= limit) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  }
  Result reap() {
    Result r;
    int status = 0;
    if (pid_ > 0 && ::waitpid(pid_, &status, 0) == pid_) {
      pid_ = -1;
      r.signal = WIFSIGNALED(status) ? WTERMSIG(status) : 0;
      r.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + r.signal;
    }
    while (!drained_) std::this_thread::sleep_for(std::chrono::milliseconds(2));  // the terminal's last output
    r.output = output();
    r.err = err();
    return r;
  }

  // A folder of its own for the output files, under the temporary directory (not a
  // support/temp_dir.hpp TempDir: benchmarks run programs too, without GoogleTest).
  static std::filesystem::path make_output_dir() {
    std::string pattern = (std::filesystem::temp_directory_path() / "fba-child-XXXXXX").string();
    if (!::mkdtemp(pattern.data()))
      throw std::runtime_error("cannot create a temporary folder " + pattern + ": " + std::strerror(errno));
    return pattern;
  }

  // Copies what the child writes on the terminal to the output file, until the terminal's last
  // writer has closed it (read fails with EIO) or the Child goes.
  void copy_terminal(int terminal, std::stop_token stop) {
    std::ofstream out(out_, std::ios::binary | std::ios::trunc);
    char buffer[4096];
    while (!stop.stop_requested()) {
      pollfd p{terminal, POLLIN, 0};
      if (::poll(&p, 1, 20) == 0) continue;
      const ssize_t n = ::read(terminal, buffer, sizeof buffer);
      if (n <= 0) break;
      out.write(buffer, n);
      out.flush();
    }
    ::close(terminal);
    drained_ = true;
  }

  std::filesystem::path dir_;  // holds the output files; removed when the Child goes
  std::filesystem::path out_;
  std::filesystem::path err_;
  pid_t pid_ = -1;
  std::atomic<bool> drained_ = true;  // false while a terminal's output is still being copied
  std::jthread copier_;               // stopped and joined before the output folder is removed
};

// Runs a program to its end: its status and output.
inline Result run(std::vector<std::string> args, ChildOptions options = {}) {
  Child child(std::move(args), std::move(options));
  return child.wait();
}

// Runs a command line through /bin/sh to its end (quoting is the caller's): its status and output.
inline Result run_shell(const std::string& command, ChildOptions options = {}) {
  return run({"/bin/sh", "-c", command}, std::move(options));
}

// Runs `body` in a forked child of the test and returns how that ended: the status is body's
// return value (0 to 255), or 128 + N when signal N ended it. For code that may crash, abort or
// run into a limit it sets (setrlimit) without taking the test down. The child leaves by _exit:
// no static destructor and no GoogleTest report of the test's copy runs there.
inline Result in_child_process(const std::function<int()>& body) {
  Result r;
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error(std::string("fork failed: ") + std::strerror(errno));
  if (pid == 0) ::_exit(body());
  int status = 0;
  if (::waitpid(pid, &status, 0) != pid) return r;
  r.signal = WIFSIGNALED(status) ? WTERMSIG(status) : 0;
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + r.signal;
  return r;
}

}  // namespace fba::test
