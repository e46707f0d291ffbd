// fba-canopen-arm-emulator: plays a CANopen arm (CiA 402 drives, one per joint) so that the CANopen
// driver can be tried without the robot. By default it is an SLCAN adapter on a new pseudo-terminal
// whose path it prints (give that path to the driver as it would /dev/ttyUSB0); with --socketcan it
// sits on a kernel CAN interface (vcan0) instead. Faults can be scheduled to try the driver's
// reactions. Ends on SIGINT or SIGTERM.
#include <unistd.h>

#include <cstdio>
#include <functional>
#include <memory>
#include <iostream>
#include <string>
#include <vector>

#include "fba/can/pty.hpp"
#include "fba/can/slcan_adapter.hpp"
#include "fba/can/socketcan.hpp"
#include "fba/emulators/canopen_arm.hpp"
#include "fba/emulators/program.hpp"

namespace {

constexpr const char* kUsage = R"(usage: fba-canopen-arm-emulator [options]
  --nodes LIST            node ids of the drives, comma separated (default 1,2,3,4,5,6)
  --link PATH             also make PATH a symbolic link to the pseudo-terminal (replaced if it is a link)
  --socketcan IFACE       use a kernel CAN interface (can0, vcan0) instead of SLCAN on a pseudo-terminal
  --heartbeat-ms N        heartbeat period after a reset, ms (default 100; 0: none)
  --velocity N            profile velocity after a reset, units/s (default 100000)
  --silence-after S:NODE  after S seconds, NODE stops answering (heartbeat silence)
  --fault-after S:NODE:CODE  after S seconds, NODE faults with the EMCY error CODE (hex, e.g. 2310)
  --reboot-after S:NODE    after S seconds, NODE reboots (a power glitch: defaults, boot-up, pre-operational)
  --garbage-every S       put a burst of noise on the line every S seconds
  --disconnect-after S    close the line after S seconds (a pulled cable)
  --ignore-set-points-after S:NODE  after S seconds, NODE takes no more set-points (no acknowledge)
  --fault-at-start NODE:CODE  NODE is in fault from power-on, error code CODE (hex) in 0x603F
  --positions LIST        where each drive's joint stands at power-on, drive units, in --nodes order (default all 0)
  --device-type NODE:HEX  NODE's device type (0x1000; default 00020192, a CiA 402 servo drive)
  --silent NODE           NODE never answers (as if it were not on the bus)
  --exit-with-parent      end when the program that started this one ends
)";

const fba::emulators::ProgramOptions kCli{"fba-canopen-arm-emulator", kUsage};

double seconds(const std::string& text, const std::string& option) { return kCli.number(text, option, 0, 1e6); }

}  // namespace

int main(int argc, char** argv) {
  fba::emulators::CanopenArmOptions options;
  std::string socketcan;
  std::vector<fba::emulators::ScheduledFault> schedule;
  using fba::emulators::CanopenArmEmulator;
  CanopenArmEmulator* emulator = nullptr;  // the actions below run once it exists
  std::vector<std::string> positions;       // --positions, read once --nodes is known
  // An option S:NODE: `act` on the node S seconds in.
  const auto on_node_after = [&](const std::string& a, const std::string& v, void (CanopenArmEmulator::*act)(int)) {
    const auto p = kCli.fields(v, a, 2, "S:NODE");
    const int node = kCli.integer(p[1], a, 1, 127);
    schedule.push_back({seconds(p[0], a), [&emulator, node, act] { (emulator->*act)(node); }});
  };
  const auto common = kCli.read(argc, argv, {}, [&](const std::string& a, const std::string& v) {
    if (a == "--nodes") {
      options.nodes.clear();
      for (const auto& id : kCli.split(v, ',')) options.nodes.push_back(kCli.integer(id, a, 1, 127));
    } else if (a == "--socketcan") {
      socketcan = v;
    } else if (a == "--heartbeat-ms") {
      options.heartbeat_ms = static_cast<std::uint16_t>(kCli.integer(v, a, 0, 65535));
    } else if (a == "--velocity") {
      options.profile_velocity = static_cast<std::uint32_t>(kCli.integer(v, a, 1, 2'000'000'000));
    } else if (a == "--silence-after") {
      on_node_after(a, v, &CanopenArmEmulator::silence);
    } else if (a == "--fault-after") {
      const auto p = kCli.fields(v, a, 3, "S:NODE:CODE");
      const int node = kCli.integer(p[1], a, 1, 127);
      const auto code = static_cast<std::uint16_t>(kCli.integer(p[2], a, 0, 0xFFFF, 16));
      schedule.push_back({seconds(p[0], a), [&emulator, node, code] { emulator->inject_fault(node, code); }});
    } else if (a == "--reboot-after") {
      on_node_after(a, v, &CanopenArmEmulator::reboot);
    } else if (a == "--garbage-every") {
      const double s = seconds(v, a);
      if (s <= 0) kCli.fail(a + " must be more than 0 seconds");
      schedule.push_back({s, [&emulator] { emulator->inject_garbage(); }, s});
    } else if (a == "--disconnect-after") {
      schedule.push_back({seconds(v, a), [&emulator] { emulator->disconnect(); }});
    } else if (a == "--ignore-set-points-after") {
      on_node_after(a, v, &CanopenArmEmulator::ignore_set_points);
    } else if (a == "--fault-at-start") {
      const auto p = kCli.fields(v, a, 2, "NODE:CODE");
      options.fault_at_start[kCli.integer(p[0], a, 1, 127)] = static_cast<std::uint16_t>(kCli.integer(p[1], a, 1, 0xFFFF, 16));
    } else if (a == "--positions") {
      positions = kCli.split(v, ',');
    } else if (a == "--device-type") {
      const auto p = kCli.fields(v, a, 2, "NODE:HEX");
      options.device_type[kCli.integer(p[0], a, 1, 127)] = static_cast<std::uint32_t>(kCli.integer(p[1], a, 0, 0x7FFFFFFF, 16));
    } else if (a == "--silent") {
      options.silent.push_back(kCli.integer(v, a, 1, 127));
    } else {
      return false;
    }
    return true;
  });
  if (!positions.empty()) {
    if (positions.size() != options.nodes.size())
      kCli.fail("--positions gives " + std::to_string(positions.size()) + " positions for " + std::to_string(options.nodes.size()) +
                " nodes; give one a node, in --nodes order");
    for (std::size_t i = 0; i < positions.size(); ++i)
      options.position_at_start[options.nodes[i]] = static_cast<std::int32_t>(kCli.integer(positions[i], "--positions", -2'000'000'000, 2'000'000'000));
  }
  const std::string& link = common.link;
  return fba::emulators::run_program(kCli, "CANopen arm emulator", [&] {
    std::unique_ptr<fba::can::CanBus> bus;
    std::function<void()> noise;
    fba::can::Pty pty;
    if (!socketcan.empty()) {
      auto socket = fba::can::open_socketcan(socketcan);
      noise = fba::emulators::noise_for(*socket);
      bus = std::move(socket);
      std::cout << "CANopen arm emulator: nodes on SocketCAN " << socketcan << std::endl;
    } else {
      pty = fba::can::open_pty();
      auto adapter =
          std::make_unique<fba::can::slcan::SlcanAdapter>(std::move(pty.master), "emulator:" + pty.slave_path);
      noise = fba::emulators::noise_for(*adapter);
      bus = std::move(adapter);
      fba::emulators::link_terminal(pty.slave_path, link);
      std::cout << "CANopen arm emulator: SLCAN adapter on " << pty.slave_path
                << (link.empty() ? "" : " (link " + link + ")") << std::endl;
    }
    fba::emulators::CanopenArmEmulator emu(*bus, options, noise);
    emulator = &emu;
    return fba::emulators::run_device([&] { return emu.run(); }, [&] { emu.stop(); }, schedule, link, common.exit_with_parent);
  });
}
