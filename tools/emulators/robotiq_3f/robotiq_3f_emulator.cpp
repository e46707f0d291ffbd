// fba-robotiq-3f-emulator: plays a Robotiq 3-Finger Adaptive Gripper, a Modbus RTU server on a new
// pseudo-terminal whose path it prints (give that path to hw.robotiq_3f as it would /dev/ttyUSB0),
// with an object between the fingers. Faults can be scheduled to try the driver's reactions. Ends on
// SIGINT or SIGTERM.
#include <signal.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <functional>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include "fba/can/pty.hpp"
#include "fba/emulators/robotiq_3f.hpp"

namespace {

constexpr const char* kUsage = R"(usage: fba-robotiq-3f-emulator [options]
  --slave N               Modbus slave id (default 9)
  --link PATH             also make PATH a symbolic link to the pseudo-terminal (replaced if it is a link)
  --activation-s S        how long activation takes, seconds (default 1)
  --object-width M        the object's diameter, metres (default 0.06)
  --object-offset M       the object's centre from the hand's, towards the thumb (finger A), metres (default 0)
  --no-object             nothing between the fingers
  --max-aperture M        thumb-to-fingers opening fully open, metres (default 0.155)
  --max-spread M          finger B to finger C with the scissor at 0, metres (default 0.12)
  --silence-after S       after S seconds, stop answering
  --bad-crc-after S:N     after S seconds, send the next N answers with a wrong CRC (N = -1: all)
  --garbage-every S       put a burst of noise before an answer every S seconds
  --fault-after S:CODE    after S seconds, report fault CODE (hex, e.g. 0D) and stop moving until a reset
  --drop-after S          after S seconds, the object slips out of the fingers
  --disconnect-after S    close the line after S seconds (a pulled cable)
)";

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }

[[noreturn]] void usage_error(const std::string& message) {
  std::cerr << "fba-robotiq-3f-emulator: " << message << "\n" << kUsage;
  std::exit(2);
}

double number(const std::string& text, const std::string& option, double lo, double hi) {
  try {
    std::size_t used = 0;
    const double v = std::stod(text, &used);
    if (used == text.size() && v >= lo && v <= hi) return v;
  } catch (const std::exception&) {
  }
  usage_error(option + ": '" + text + "' is not a number in " + std::to_string(lo) + ".." + std::to_string(hi));
}

int integer(const std::string& text, const std::string& option, int lo, int hi, int base = 10) {
  try {
    std::size_t used = 0;
    const long v = std::stol(text, &used, base);
    if (used == text.size() && v >= lo && v <= hi) return static_cast<int>(v);
  } catch (const std::exception&) {
  }
  usage_error(option + ": '" + text + "' is not an integer in " + std::to_string(lo) + ".." + std::to_string(hi));
}

std::pair<std::string, std::string> pair_of(const std::string& v, const std::string& option, const char* form) {
  const auto colon = v.find(':');
  if (colon == std::string::npos) usage_error(option + " takes " + form + ", not '" + v + "'");
  return {v.substr(0, colon), v.substr(colon + 1)};
}

struct Scheduled {
  double at;
  std::function<void()> action;
  double period = 0;  // > 0: repeats
};

}  // namespace

int main(int argc, char** argv) {
  fba::emulators::Robotiq3fOptions options;
  std::string link;
  std::vector<Scheduled> schedule;
  fba::emulators::Robotiq3fEmulator* emulator = nullptr;  // the actions below run once it exists
  std::vector<std::string> args(argv + 1, argv + argc);
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "-h" || a == "--help") {
      std::cout << kUsage;
      return 0;
    }
    if (a == "--no-object") {
      options.object = false;
      continue;
    }
    if (i + 1 >= args.size()) usage_error(a.empty() ? "an empty argument" : "'" + a + "' needs a value or is unknown");
    const std::string v = args[++i];
    constexpr double kLong = 1e6;
    if (a == "--slave") {
      options.slave_id = integer(v, a, 1, 247);
    } else if (a == "--link") {
      link = v;
    } else if (a == "--activation-s") {
      options.activation_s = number(v, a, 0, 120);
    } else if (a == "--object-width") {
      options.object_width = number(v, a, 0.001, 1);
    } else if (a == "--object-offset") {
      options.object_offset = number(v, a, -1, 1);
    } else if (a == "--max-aperture") {
      options.max_aperture = number(v, a, 0.01, 1);
    } else if (a == "--max-spread") {
      options.max_spread = number(v, a, 0.01, 1);
    } else if (a == "--silence-after") {
      schedule.push_back({number(v, a, 0, kLong), [&emulator] { emulator->silence(); }});
    } else if (a == "--bad-crc-after") {
      const auto [s, n] = pair_of(v, a, "S:N");
      const int count = integer(n, a, -1, 1'000'000);
      schedule.push_back({number(s, a, 0, kLong), [&emulator, count] { emulator->corrupt_replies(count); }});
    } else if (a == "--garbage-every") {
      const double s = number(v, a, 0.001, kLong);
      schedule.push_back({s, [&emulator] { emulator->inject_garbage(); }, s});
    } else if (a == "--fault-after") {
      const auto [s, c] = pair_of(v, a, "S:CODE");
      const int code = integer(c, a, 1, 0x0F, 16);
      schedule.push_back({number(s, a, 0, kLong), [&emulator, code] { emulator->inject_fault(code); }});
    } else if (a == "--drop-after") {
      schedule.push_back({number(v, a, 0, kLong), [&emulator] { emulator->remove_object(); }});
    } else if (a == "--disconnect-after") {
      schedule.push_back({number(v, a, 0, kLong), [&emulator] { emulator->disconnect(); }});
    } else {
      usage_error("unknown option '" + a + "'");
    }
  }

  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);

  try {
    fba::can::Pty pty = fba::can::open_pty();
    if (!link.empty()) {
      std::error_code ec;
      if (std::filesystem::is_symlink(link, ec)) std::filesystem::remove(link, ec);
      std::filesystem::create_symlink(pty.slave_path, link);
    }
    fba::emulators::Robotiq3fEmulator emu(std::move(pty.master), "emulator:" + pty.slave_path, options);
    emulator = &emu;
    std::cout << "Robotiq 3-Finger emulator: Modbus RTU slave " << options.slave_id << " on " << pty.slave_path
              << (link.empty() ? "" : " (link " + link + ")") << std::endl;
    std::string reason;
    std::atomic<bool> ended{false};
    std::thread runner([&] {
      reason = emu.run();
      ended = true;
    });
    const auto start = std::chrono::steady_clock::now();
    while (!g_stop && !ended) {
      const double now = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      for (auto& s : schedule)
        if (s.at >= 0 && now >= s.at) {
          s.action();
          s.at = s.period > 0 ? s.at + s.period : -1;
        }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    emu.stop();
    runner.join();
    if (!link.empty()) std::filesystem::remove(link);
    std::cout << "Robotiq 3-Finger emulator: " << (g_stop ? "stopped" : reason) << std::endl;
  } catch (const std::exception& e) {
    std::cerr << "fba-robotiq-3f-emulator: " << e.what() << std::endl;
    return 1;
  }
  return 0;
}
