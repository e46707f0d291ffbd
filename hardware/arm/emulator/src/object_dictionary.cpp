// The CiA 301 and CiA 402 objects of an emulated drive, as a reset leaves them.
#include <string>

#include "node.hpp"

namespace fba::emulators::detail {

namespace {

void add(std::map<std::uint32_t, Entry>& od, std::uint16_t index, std::uint8_t sub, std::uint8_t size,
         const char* access, bool mappable, std::uint32_t value) {
  const std::string a = access;
  od[key(index, sub)] = Entry{size, a != "wo", a != "ro", mappable, value};
}

}  // namespace

// The communication objects (0x1000..0x1FFF) after a reset of the node or of its communication,
// with the PDOs' run-time state; the drive is not touched (CiA 301: NMT reset communication resets
// the communication area only, so a drive in fault stays in fault).
void reset_communication(CanopenArmEmulator::Node& n, const CanopenArmOptions& o) {
  auto& od = n.od;
  std::erase_if(od, [](const auto& e) { return (e.first >> 8) < 0x2000; });
  const auto id = static_cast<std::uint32_t>(n.id);
  const auto type = o.device_type.find(n.id);
  add(od, 0x1000, 0, 4, "ro", false, type == o.device_type.end() ? 0x00020192 : type->second);  // CiA 402, servo
  add(od, 0x1001, 0, 1, "ro", true, 0);            // error register
  add(od, 0x1017, 0, 2, "rw", false, o.heartbeat_ms);
  add(od, 0x1018, 0, 1, "ro", false, 4);
  add(od, 0x1018, 1, 4, "ro", false, 0x00000FBA);  // vendor id
  add(od, 0x1018, 2, 4, "ro", false, 0x00000402);  // product code
  add(od, 0x1018, 3, 4, "ro", false, 0x00010000);  // revision
  add(od, 0x1018, 4, 4, "ro", false, id);          // serial number
  for (std::uint16_t p = 0; p < 4; ++p) {
    const std::uint32_t rpdo = 0x200 + 0x100 * p + id, tpdo = 0x180 + 0x100 * p + id;
    add(od, 0x1400 + p, 0, 1, "ro", false, 2);
    add(od, 0x1400 + p, 1, 4, "rw", false, rpdo | 0x80000000U);  // invalid until configured
    add(od, 0x1400 + p, 2, 1, "rw", false, 0xFF);
    add(od, 0x1600 + p, 0, 1, "rw", false, 0);
    add(od, 0x1800 + p, 0, 1, "ro", false, 5);
    add(od, 0x1800 + p, 1, 4, "rw", false, tpdo | 0x80000000U);
    add(od, 0x1800 + p, 2, 1, "rw", false, 0xFF);
    add(od, 0x1800 + p, 3, 2, "rw", false, 0);  // inhibit time
    add(od, 0x1800 + p, 5, 2, "rw", false, 0);  // event timer
    add(od, 0x1A00 + p, 0, 1, "rw", false, 0);
    for (std::uint8_t s = 1; s <= 8; ++s) {
      add(od, 0x1600 + p, s, 4, "rw", false, 0);
      add(od, 0x1A00 + p, s, 4, "rw", false, 0);
    }
  }
  n.tpdo_syncs = {};
  n.tpdo_last = {};
  n.rpdo_pending = {};
}

// The drive's objects and state after a reset of the node (or power-on): the joint stays where it is.
void reset_application(CanopenArmEmulator::Node& n, const CanopenArmOptions& o) {
  auto& od = n.od;
  std::erase_if(od, [](const auto& e) { return (e.first >> 8) >= 0x2000; });
  add(od, 0x603F, 0, 2, "ro", true, 0);  // error code
  add(od, 0x6040, 0, 2, "rw", true, 0);  // controlword
  add(od, 0x6041, 0, 2, "ro", true, 0);  // statusword
  add(od, 0x6060, 0, 1, "rw", true, 0);  // modes of operation
  add(od, 0x6061, 0, 1, "ro", true, 0);  // modes of operation display
  add(od, 0x60C2, 0, 1, "ro", false, 2);     // interpolation time period: value * 10^index seconds
  add(od, 0x60C2, 1, 1, "rw", false, 10);    // 10 ms
  add(od, 0x60C2, 2, 1, "rw", false, 0xFD);  // -3
  add(od, 0x6064, 0, 4, "ro", true, 0);  // position actual value
  add(od, 0x606C, 0, 4, "ro", true, 0);  // velocity actual value
  add(od, 0x607A, 0, 4, "rw", true, 0);  // target position
  add(od, 0x607D, 0, 1, "ro", false, 2);
  add(od, 0x607D, 1, 4, "rw", false, static_cast<std::uint32_t>(o.min_position));
  add(od, 0x607D, 2, 4, "rw", false, static_cast<std::uint32_t>(o.max_position));
  add(od, 0x6081, 0, 4, "rw", true, o.profile_velocity);
  add(od, 0x6083, 0, 4, "rw", true, 10 * o.profile_velocity);
  add(od, 0x6084, 0, 4, "rw", true, 10 * o.profile_velocity);
  n.drive = Drive::switch_on_disabled;
  n.controlword = 0;
  n.hold();
  n.acknowledged = n.limited = false;
}

void reset_dictionary(CanopenArmEmulator::Node& n, const CanopenArmOptions& o) {
  reset_communication(n, o);
  reset_application(n, o);
}

}  // namespace fba::emulators::detail
