// What every emulator program does around its device: read options with clear errors, link the
// pseudo-terminal where asked, run the device until SIGINT/SIGTERM or until it ends by itself,
// and fire the scheduled faults on time meanwhile. Header only: each program is one file.
#pragma once

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <iostream>
#include <map>
#include <string>
#include <thread>
#include <vector>

namespace fba::emulators {

// The options every emulator program takes: a driver's launcher starts one with --link PATH
// --exit-with-parent (launcher.hpp), and a person may give them too.
struct CommonOptions {
  std::string link;  // where to link the pseudo-terminal ("": nowhere)
  bool exit_with_parent = false;
};

// Option parsing for one program: every mistake ends the program with exit 2, the reason and the usage.
struct ProgramOptions {
  const char* name;   // "fba-robotiq-3f-emulator"
  const char* usage;  // the whole usage text

  [[noreturn]] void fail(const std::string& message) const {
    std::cerr << name << ": " << message << "\n" << usage;
    std::exit(2);
  }
  double number(const std::string& text, const std::string& option, double lo, double hi) const {
    try {
      std::size_t used = 0;
      const double v = std::stod(text, &used);
      if (used == text.size() && v >= lo && v <= hi) return v;
    } catch (const std::exception&) {
    }
    fail(option + ": '" + text + "' is not a number in " + std::to_string(lo) + ".." + std::to_string(hi));
  }
  int integer(const std::string& text, const std::string& option, int lo, int hi, int base = 10) const {
    try {
      std::size_t used = 0;
      const long v = std::stol(text, &used, base);
      if (used == text.size() && v >= lo && v <= hi) return static_cast<int>(v);
    } catch (const std::exception&) {
    }
    fail(option + ": '" + text + "' is not an integer in " + std::to_string(lo) + ".." + std::to_string(hi));
  }
  static std::vector<std::string> split(const std::string& text, char separator) {
    std::vector<std::string> out;
    std::size_t from = 0;
    for (std::size_t at; (at = text.find(separator, from)) != std::string::npos; from = at + 1)
      out.push_back(text.substr(from, at - from));
    out.push_back(text.substr(from));
    return out;
  }
  // "S:NODE" and the like: exactly `parts` pieces between ':'.
  std::vector<std::string> fields(const std::string& text, const std::string& option, std::size_t parts, const char* form) const {
    auto out = split(text, ':');
    if (out.size() != parts) fail(option + " takes " + form + ", not '" + text + "'");
    return out;
  }

  // Reads the command line argv[1..argc): -h or --help prints the usage and ends the program (exit 0);
  // --link PATH and --exit-with-parent fill the result; an option named in `flags` takes no value and
  // runs its action; any other takes the next argument as its value and goes to `option(name, value)`,
  // which returns false for a name it does not know. A mistake ends the program through fail().
  CommonOptions read(int argc, char** argv, const std::map<std::string, std::function<void()>>& flags,
                     const std::function<bool(const std::string&, const std::string&)>& option) const {
    CommonOptions common;
    const std::vector<std::string> args(argv + 1, argv + argc);
    for (std::size_t i = 0; i < args.size(); ++i) {
      const std::string& a = args[i];
      if (a == "-h" || a == "--help") {
        std::cout << usage;
        std::exit(0);
      }
      if (a == "--exit-with-parent") {
        common.exit_with_parent = true;
        continue;
      }
      if (const auto flag = flags.find(a); flag != flags.end()) {
        flag->second();
        continue;
      }
      if (i + 1 >= args.size()) fail(a.empty() ? "an empty argument" : "'" + a + "' needs a value or is unknown");
      const std::string& v = args[++i];
      if (a == "--link")
        common.link = v;
      else if (!option(a, v))
        fail("unknown option '" + a + "'");
    }
    return common;
  }
};

// A fault to inject `at` seconds after the start; again every `period` seconds when that is > 0.
struct ScheduledFault {
  double at;
  std::function<void()> action;
  double period = 0;
};

// Makes `link` (if given) a symbolic link to the pseudo-terminal, replacing an older link.
inline void link_terminal(const std::string& slave_path, const std::string& link) {
  if (link.empty()) return;
  std::error_code ec;
  if (std::filesystem::is_symlink(link, ec)) std::filesystem::remove(link, ec);
  std::filesystem::create_symlink(slave_path, link);
}

namespace detail {
inline std::atomic<bool> stop_signal{false};
inline void on_stop_signal(int) { stop_signal = true; }
}  // namespace detail

// SIGINT and SIGTERM end run_device's loop instead of the process: before the terminal is opened,
// so that a stop never leaves a link behind.
inline void catch_stop_signals() {
  struct sigaction sa {};
  sa.sa_handler = detail::on_stop_signal;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

// Runs `run` (the device; returns why it ended) on its own thread until it ends or a stop signal
// comes, firing `faults` on time; then `stop` and the join. Returns "stopped" or the device's reason,
// and removes `link`. With `exit_with_parent`, it also ends when the process that started it has
// ended (a driver that started the emulator and was killed): its parent is no longer the same.
inline std::string run_device(const std::function<std::string()>& run, const std::function<void()>& stop,
                              std::vector<ScheduledFault> faults, const std::string& link, bool exit_with_parent = false) {
  const pid_t parent = ::getppid();
  bool orphaned = false;
  std::string reason;
  std::atomic<bool> ended{false};
  std::thread runner([&] {
    reason = run();
    ended = true;
  });
  const auto start = std::chrono::steady_clock::now();
  while (!detail::stop_signal && !ended && !orphaned) {
    orphaned = exit_with_parent && ::getppid() != parent;
    const double now = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    for (auto& f : faults)
      if (f.at >= 0 && now >= f.at) {
        f.action();
        f.at = f.period > 0 ? f.at + f.period : -1;
      }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  stop();
  runner.join();
  if (!link.empty()) std::filesystem::remove(link);
  if (orphaned) return "stopped: the program that started it has ended";
  return detail::stop_signal ? "stopped" : reason;
}

// The rest of an emulator program's main once its options are read: the stop signals caught (before
// the terminal is opened), then `device`, which opens the device and runs it (run_device) and returns
// why it ended, printed as "<title>: <reason>". Returns main's exit status: 0, or 1 when `device`
// throws, with "<program>: <what>" on stderr.
inline int run_program(const ProgramOptions& cli, const std::string& title, const std::function<std::string()>& device) {
  catch_stop_signals();
  try {
    const std::string end = device();
    std::cout << title << ": " << end << std::endl;
  } catch (const std::exception& e) {
    std::cerr << cli.name << ": " << e.what() << std::endl;
    return 1;
  }
  return 0;
}

}  // namespace fba::emulators
