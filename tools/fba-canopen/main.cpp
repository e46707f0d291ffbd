// fba-canopen: a CANopen master on the command line, on the transport and master the drivers use.
#include <charconv>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "fba/can/open_bus.hpp"
#include "fba/canopen/cia402.hpp"
#include "fba/canopen/master.hpp"

namespace {

using namespace std::chrono_literals;
namespace co = fba::canopen;

constexpr const char* kUsage = R"(usage: fba-canopen [--bus BUS] [--bitrate N] [--timeout-ms N] COMMAND
  --bus BUS        can0, socketcan:can0, or slcan:/dev/ttyUSB0 (default can0)
  --bitrate N      the CAN bitrate an SLCAN adapter is set to (default 500000)
  --timeout-ms N   SDO timeout (default 200)
commands:
  scan [MS]                        list the nodes heard (heartbeat or boot-up) within MS ms (default 1000)
  nmt start|stop|preop|reset|reset-comm NODE   (NODE 0: every node)
  read NODE INDEX[:SUB]            expedited SDO upload; INDEX and SUB in hex (6041, 1018:04)
  write NODE INDEX[:SUB] SIZE VALUE   expedited SDO download of SIZE (1, 2, 4) bytes; VALUE decimal or 0x hex
  status NODE                      a CiA 402 drive's state, position and error code
  move NODE TARGET [VELOCITY]      start the node, set profile position mode, enable the drive and make a
                                   profile position move (a drive in fault is refused, naming its error code)
  reset NODE                       reset a drive's fault (naming the error code it had)
  monitor SECONDS                  print NMT states, EMCY, lost heartbeats and reboots as they come
)";

[[noreturn]] void usage(const std::string& message) {
  std::cerr << "fba-canopen: " << message << "\n" << kUsage;
  std::exit(2);
}

long long number(const std::string& text, const char* what, long long lo, long long hi, int base = 10) {
  std::string t = text;
  bool negative = false;
  if (!t.empty() && t[0] == '-') {
    negative = true;
    t.erase(0, 1);
  }
  if (base == 10 && t.rfind("0x", 0) == 0) {
    base = 16;
    t.erase(0, 2);
  }
  long long v = 0;
  const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v, base);
  if (negative) v = -v;
  if (t.empty() || ec != std::errc() || end != t.data() + t.size() || v < lo || v > hi)
    usage(fmt::format("{} '{}' is not a {} number in {}..{}", what, text, base == 16 ? "hexadecimal" : "decimal", lo,
                      hi));
  return v;
}

int node_arg(const std::vector<std::string>& a, std::size_t i, bool broadcast = false) {
  if (i >= a.size()) usage("a node id is missing");
  return static_cast<int>(number(a[i], "node id", broadcast ? 0 : 1, 127));
}

std::pair<std::uint16_t, std::uint8_t> object_arg(const std::vector<std::string>& a, std::size_t i) {
  if (i >= a.size()) usage("an object INDEX[:SUB] is missing");
  const std::string& s = a[i];
  const auto colon = s.find(':');
  const auto index = static_cast<std::uint16_t>(number(s.substr(0, colon), "index", 0, 0xFFFF, 16));
  const auto sub =
      colon == std::string::npos ? 0 : static_cast<std::uint8_t>(number(s.substr(colon + 1), "sub-index", 0, 0xFF, 16));
  return {index, sub};
}

int run(co::Master& m, const std::vector<std::string>& a) {
  const std::string& command = a[0];
  if (command == "scan") {
    const auto ms = a.size() > 1 ? number(a[1], "time", 1, 600000) : 1000;
    m.spin_for(std::chrono::milliseconds(ms));
    int found = 0;
    for (int node = 1; node <= co::kMaxNode; ++node)
      if (m.state(node) != co::NmtState::unknown) {
        fmt::print("node {}: {}\n", node, co::to_string(m.state(node)));
        ++found;
      }
    if (found == 0) fmt::print("no node heard within {} ms (nodes with no heartbeat show only at boot-up)\n", ms);
    return 0;
  }
  if (command == "nmt") {
    if (a.size() < 3) usage("nmt takes a command and a node");
    const std::pair<const char*, co::NmtCommand> commands[] = {{"start", co::NmtCommand::start},
                                                               {"stop", co::NmtCommand::stop},
                                                               {"preop", co::NmtCommand::pre_operational},
                                                               {"reset", co::NmtCommand::reset_node},
                                                               {"reset-comm", co::NmtCommand::reset_communication}};
    for (const auto& [name, c] : commands)
      if (a[1] == name) {
        m.nmt(c, node_arg(a, 2, true));
        return 0;
      }
    usage("unknown NMT command '" + a[1] + "'");
  }
  if (command == "read") {
    const int node = node_arg(a, 1);
    const auto [index, sub] = object_arg(a, 2);
    const auto bytes = m.sdo_upload(node, index, sub);
    std::uint32_t v = 0;
    for (std::size_t i = 0; i < bytes.size(); ++i) v |= static_cast<std::uint32_t>(bytes[i]) << (8 * i);
    fmt::print("node {} 0x{:04X}:{:02X} = {} (0x{:0{}X}, {} bytes)\n", node, index, sub, v, v, 2 * bytes.size(),
               bytes.size());
    return 0;
  }
  if (command == "write") {
    const int node = node_arg(a, 1);
    const auto [index, sub] = object_arg(a, 2);
    if (a.size() < 5) usage("write takes NODE INDEX[:SUB] SIZE VALUE");
    const auto size = number(a[3], "size", 1, 4);
    if (size == 3) usage("size is 1, 2 or 4 bytes");
    const auto value = static_cast<std::uint32_t>(number(a[4], "value", -2147483648LL, 4294967295LL));
    std::vector<std::uint8_t> bytes;
    for (int i = 0; i < size; ++i) bytes.push_back(static_cast<std::uint8_t>(value >> (8 * i)));
    m.sdo_download(node, index, sub, bytes);
    return 0;
  }
  if (command == "status") {
    co::cia402::Drive drive(m, node_arg(a, 1));
    const std::uint16_t s = drive.statusword();
    const std::uint16_t code = drive.error_code();
    fmt::print("node {}: {} (statusword 0x{:04X}), position {}, error code 0x{:04X} ({})\n", drive.node(),
               co::cia402::to_string(co::cia402::decode(s)), s, drive.position(), code, co::emcy_name(code));
    return 0;
  }
  if (command == "move") {
    const int node = node_arg(a, 1);
    if (a.size() < 3) usage("move takes NODE TARGET [VELOCITY]");
    const auto target = static_cast<std::int32_t>(number(a[2], "target", INT32_MIN, INT32_MAX));
    const auto velocity = static_cast<std::uint32_t>(a.size() > 3 ? number(a[3], "velocity", 1, UINT32_MAX) : 100000);
    m.nmt(co::NmtCommand::start, node);
    co::cia402::Drive drive(m, node);
    drive.set_profile(velocity, 10 * velocity);  // the mode before "operation enabled"
    try {
      drive.enable(2s);
    } catch (const co::cia402::DriveFault& e) {
      throw co::Error(std::string(e.what()) + "; 'fba-canopen reset " + std::to_string(node) + "' resets it");
    }
    drive.move_to(target, 600s);
    fmt::print("node {}: at {}\n", node, drive.position());
    return 0;
  }
  if (command == "reset") {
    co::cia402::Drive drive(m, node_arg(a, 1));
    const std::uint16_t s = drive.statusword();
    if (co::cia402::decode(s) != co::cia402::State::fault) {
      fmt::print("node {}: not in fault ({}, statusword 0x{:04X}): nothing to reset\n", drive.node(),
                 co::cia402::to_string(co::cia402::decode(s)), s);
      return 0;
    }
    const std::uint16_t code = drive.error_code();
    drive.fault_reset(2s);
    fmt::print("node {}: fault reset (its error code was 0x{:04X}: {})\n", drive.node(), code, co::emcy_name(code));
    return 0;
  }
  if (command == "monitor") {
    if (a.size() < 2) usage("monitor takes a number of seconds");
    const auto seconds = number(a[1], "time", 1, 86400);
    std::map<int, co::NmtState> seen;
    std::size_t emcy = 0, faults = 0;
    for (int node = 1; node <= co::kMaxNode; ++node) m.watch_heartbeat(node, 3s);
    const auto end = co::Clock::now() + std::chrono::seconds(seconds);
    while (co::Clock::now() < end) {
      m.spin_for(50ms);
      for (int node = 1; node <= co::kMaxNode; ++node)
        if (m.state(node) != co::NmtState::unknown && seen[node] != m.state(node)) {
          seen[node] = m.state(node);
          fmt::print("node {}: {}\n", node, co::to_string(m.state(node)));
        }
      for (; emcy < m.emergencies().size(); ++emcy)
        fmt::print("node {}: {}\n", m.emergencies()[emcy].node, m.emergencies()[emcy].describe());
      for (; faults < m.faults().size(); ++faults)
        if (m.faults()[faults].kind != co::Fault::Kind::emergency && seen.count(m.faults()[faults].node))
          fmt::print("{}\n", m.faults()[faults].message);  // EMCY is printed above
    }
    return 0;
  }
  usage("unknown command '" + command + "'");
}

}  // namespace

int main(int argc, char** argv) {
  std::string bus_spec = "can0";
  int bitrate = 500000;
  int timeout_ms = 200;
  std::vector<std::string> args;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "-h" || a == "--help") {
      std::cout << kUsage;
      return 0;
    }
    if (a == "--bus" || a == "--bitrate" || a == "--timeout-ms") {
      if (i + 1 >= argc) usage(a + " needs a value");
      const std::string v = argv[++i];
      if (a == "--bus")
        bus_spec = v;
      else if (a == "--bitrate")
        bitrate = static_cast<int>(number(v, "bitrate", 10000, 1000000));
      else
        timeout_ms = static_cast<int>(number(v, "timeout", 1, 60000));
    } else {
      args.push_back(a);
    }
  }
  if (args.empty()) usage("no command given");
  try {
    auto bus = fba::can::open_bus(bus_spec, bitrate);
    co::Master master(*bus, co::MasterOptions{.sdo_timeout = std::chrono::milliseconds(timeout_ms)});
    return run(master, args);
  } catch (const std::invalid_argument& e) {
    std::cerr << "fba-canopen: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "fba-canopen: " << e.what() << "\n";
    return 1;
  }
}
