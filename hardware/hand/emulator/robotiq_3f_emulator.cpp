// fba-robotiq-3f-emulator: plays a Robotiq 3-Finger Adaptive Gripper, a Modbus RTU server on a new
// pseudo-terminal whose path it prints (give that path to hw.robotiq_3f as it would /dev/ttyUSB0),
// with an object between the fingers. Faults can be scheduled to try the driver's reactions. Ends on
// SIGINT or SIGTERM.

#include <functional>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "fba/can/pty.hpp"
#include "fba/emulators/program.hpp"
#include "fba/emulators/robotiq_3f.hpp"

namespace {

constexpr const char* kUsage = R"(usage: fba-robotiq-3f-emulator [options]
  --slave N               Modbus slave id (default 9)
  --link PATH             also make PATH a symbolic link to the pseudo-terminal (replaced if it is a link)
  --activation-s S        how long activation takes, seconds (default 1)
  --never-activate        activation starts and never ends (a hand that cannot activate)
  --object-width M        the object's extent from the thumb's side to the fingers', metres (default 0.06)
  --object-length M       its extent along the spread, finger B to C, metres (default: the width, a cylinder)
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
  --stall-aperture M      the fingers stall on an object at this thumb-to-fingers aperture, metres, whatever
                          their spread (instead of the object above): a grasp that holds
  --exit-with-parent      end when the program that started this one ends
)";

const fba::emulators::ProgramOptions kCli{"fba-robotiq-3f-emulator", kUsage};

using fba::emulators::Robotiq3fEmulator;
using fba::emulators::Robotiq3fOptions;

// The options that set a number of Robotiq3fOptions, with its range.
struct NumberOption {
  const char* name;
  double Robotiq3fOptions::*field;
  double min, max;
};
constexpr NumberOption kNumbers[] = {
    {"--activation-s", &Robotiq3fOptions::activation_s, 0, 120},
    {"--object-width", &Robotiq3fOptions::object_width, 0.001, 1},
    {"--object-length", &Robotiq3fOptions::object_length, 0.001, 1},
    {"--object-offset", &Robotiq3fOptions::object_offset, -1, 1},
    {"--max-aperture", &Robotiq3fOptions::max_aperture, 0.01, 1},
    {"--stall-aperture", &Robotiq3fOptions::stall_aperture, 0.001, 1},
    {"--max-spread", &Robotiq3fOptions::max_spread, 0.01, 1},
};

}  // namespace

int main(int argc, char** argv) {
  Robotiq3fOptions options;
  std::vector<fba::emulators::ScheduledFault> schedule;
  Robotiq3fEmulator* emulator = nullptr;  // the actions below run once it exists
  constexpr double kLong = 1e6;
  // An option S: `act` S seconds in.
  const auto after = [&](const std::string& a, const std::string& v, void (Robotiq3fEmulator::*act)()) {
    schedule.push_back({kCli.number(v, a, 0, kLong), [&emulator, act] { (emulator->*act)(); }});
  };
  const std::map<std::string, std::function<void()>> flags{{"--no-object", [&] { options.object = false; }},
                                                           {"--never-activate", [&] { options.activates = false; }}};
  const auto common = kCli.read(argc, argv, flags, [&](const std::string& a, const std::string& v) {
    for (const NumberOption& o : kNumbers)
      if (a == o.name) {
        options.*o.field = kCli.number(v, a, o.min, o.max);
        return true;
      }
    if (a == "--slave") {
      options.slave_id = kCli.integer(v, a, 1, 247);
    } else if (a == "--silence-after") {
      after(a, v, &Robotiq3fEmulator::silence);
    } else if (a == "--bad-crc-after") {
      const auto f = kCli.fields(v, a, 2, "S:N");
      const std::string &s = f[0], &n = f[1];
      const int count = kCli.integer(n, a, -1, 1'000'000);
      schedule.push_back({kCli.number(s, a, 0, kLong), [&emulator, count] { emulator->corrupt_replies(count); }});
    } else if (a == "--garbage-every") {
      const double s = kCli.number(v, a, 0.001, kLong);
      schedule.push_back({s, [&emulator] { emulator->inject_garbage(); }, s});
    } else if (a == "--fault-after") {
      const auto f = kCli.fields(v, a, 2, "S:CODE");
      const std::string &s = f[0], &c = f[1];
      const int code = kCli.integer(c, a, 1, 0x0F, 16);
      schedule.push_back({kCli.number(s, a, 0, kLong), [&emulator, code] { emulator->inject_fault(code); }});
    } else if (a == "--drop-after") {
      after(a, v, &Robotiq3fEmulator::remove_object);
    } else if (a == "--disconnect-after") {
      after(a, v, &Robotiq3fEmulator::disconnect);
    } else {
      return false;
    }
    return true;
  });
  const std::string& link = common.link;
  return fba::emulators::run_program(kCli, "Robotiq 3-Finger emulator", [&] {
    fba::can::Pty pty = fba::can::open_pty();
    fba::emulators::link_terminal(pty.slave_path, link);
    Robotiq3fEmulator emu(std::move(pty.master), "emulator:" + pty.slave_path, options);
    emulator = &emu;
    std::cout << "Robotiq 3-Finger emulator: Modbus RTU slave " << options.slave_id << " on " << pty.slave_path
              << (link.empty() ? "" : " (link " + link + ")") << std::endl;
    return fba::emulators::run_device([&] { return emu.run(); }, [&] { emu.stop(); }, schedule, link, common.exit_with_parent);
  });
}
