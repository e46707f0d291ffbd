// A program run by a test (an emulator, fba-run): its stdout and stderr on a pipe (or a
// pseudo-terminal, for what a program does on a terminal), read with a bound that detects a hang
// (not a speed check); killed and reaped when it goes out of scope.
#pragma once

#include <poll.h>
#include <pty.h>
#include <termios.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace fba::test {

// A child process with its stdout and stderr on a pipe or a terminal; killed and reaped when it
// goes out of scope.
class Child {
 public:
  // Terminal: a pseudo-terminal of 200 columns in raw mode (isatty() is true in the child, and what
  // it writes arrives unchanged: "\n" stays "\n").
  enum class Output { Pipe, Terminal };

  explicit Child(std::vector<std::string> args, Output output = Output::Pipe) {
    int fds[2];
    if (output == Output::Terminal) {
      termios raw{};
      cfmakeraw(&raw);
      winsize size{};
      size.ws_col = 200;
      size.ws_row = 50;
      if (::openpty(&fds[0], &fds[1], nullptr, &raw, &size) != 0) throw std::runtime_error("openpty failed");
    } else if (::pipe(fds) != 0) {
      throw std::runtime_error("pipe failed");
    }
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
  // Output until `needle` appears, the output ends, or `limit` passes (a hung program, not a speed check).
  std::string read_until(const std::string& needle, std::chrono::milliseconds limit = std::chrono::seconds(60)) {
    const auto deadline = std::chrono::steady_clock::now() + limit;
    while (output_.find(needle) == std::string::npos && read_more(deadline)) {
    }
    return output_;
  }
  // The whole line that holds `needle`, without its newline, once it has all come; empty if the
  // output ends or `limit` passes first (a line written in pieces is waited for whole).
  std::string read_line_with(const std::string& needle, std::chrono::milliseconds limit = std::chrono::seconds(60)) {
    const auto deadline = std::chrono::steady_clock::now() + limit;
    for (;;) {
      if (const auto at = output_.find(needle); at != std::string::npos)
        if (const auto end = output_.find('\n', at); end != std::string::npos) {
          const auto start = output_.rfind('\n', at);
          const std::size_t from = start == std::string::npos ? 0 : start + 1;
          return output_.substr(from, end - from);
        }
      if (!read_more(deadline)) return {};
    }
  }
  // The exit status after `signal` (0: none sent) once it ends; -1 if it did not end within `limit`
  // (a hang detector, not a speed check).
  int wait(int signal, std::chrono::milliseconds limit = std::chrono::seconds(60)) {
    if (signal) ::kill(pid_, signal);
    const auto deadline = std::chrono::steady_clock::now() + limit;
    for (;;) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        read_until("\x01", std::chrono::milliseconds(100));  // what is left in the pipe
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      if (std::chrono::steady_clock::now() >= deadline) return -1;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }

 private:
  // Reads what the program wrote next; false when its output ended or the deadline passed.
  bool read_more(std::chrono::steady_clock::time_point deadline) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return false;
    pollfd p{out_, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(left.count())) <= 0) return false;
    char buffer[512];
    const ssize_t n = ::read(out_, buffer, sizeof buffer);
    if (n <= 0) return false;
    output_.append(buffer, static_cast<std::size_t>(n));
    return true;
  }

  pid_t pid_ = -1;
  int out_ = -1;
  std::string output_;
};

}  // namespace fba::test
