// A CiA 402 drive of the CANopen arm emulator: its object dictionary, its NMT state, its PDOs' run-time
// state and its simulated motion; private to the emulator's sources (canopen_arm.cpp runs the bus,
// object_dictionary.cpp builds the dictionary).
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <vector>

#include "fba/emulators/canopen_arm.hpp"

namespace fba::emulators::detail {

using Clock = std::chrono::steady_clock;

// CiA 301 identifiers and codes, written here from the standard rather than shared with the
// master, so that a misreading on one side shows up as a failing test.
constexpr std::uint32_t kNmt = 0x000, kSync = 0x080, kEmcy = 0x080, kSdoTx = 0x580, kSdoRx = 0x600, kHeartbeat = 0x700;
constexpr std::uint8_t kPreOperational = 0x7F, kOperational = 0x05, kStopped = 0x04;
constexpr std::uint32_t kAbortCommand = 0x05040001, kAbortWriteOnly = 0x06010001, kAbortReadOnly = 0x06010002,
                        kAbortNoObject = 0x06020000, kAbortNotMappable = 0x06040041, kAbortPdoLength = 0x06040042,
                        kAbortParameters = 0x06040043, kAbortLength = 0x06070010, kAbortNoSub = 0x06090011,
                        kAbortValue = 0x06090030, kAbortDeviceState = 0x08000022;
// Change-driven TPDOs go at most this often (an inhibit time), so a moving joint does not flood the bus.
constexpr std::chrono::milliseconds kInhibit{10};

// CiA 402 states, as statusword bits under the 0x6F mask.
enum class Drive : std::uint16_t {
  switch_on_disabled = 0x0040,
  ready = 0x0021,
  switched_on = 0x0023,
  enabled = 0x0027,
  quick_stop = 0x0007,
  fault = 0x0008,
};

inline std::uint32_t key(std::uint16_t index, std::uint8_t sub) { return static_cast<std::uint32_t>(index) << 8 | sub; }

struct Entry {
  std::uint8_t size;  // bytes
  bool readable;
  bool writable;
  bool mappable;
  std::uint32_t value;
};

}  // namespace fba::emulators::detail

namespace fba::emulators {

struct CanopenArmEmulator::Node {
  using Clock = detail::Clock;
  using Drive = detail::Drive;
  int id;
  bool silent = false;
  std::uint8_t nmt = detail::kPreOperational;
  std::uint64_t sdo_downloads = 0;  // SDO download requests heard (each a command to the drive)
  std::map<std::uint32_t, detail::Entry> od;
  Clock::time_point last_heartbeat;
  // TPDO and RPDO run-time state, per PDO number 0..3.
  std::array<int, 4> tpdo_syncs{};
  std::array<std::vector<std::uint8_t>, 4> tpdo_last;
  std::array<Clock::time_point, 4> tpdo_time{};
  std::array<std::optional<can::Frame>, 4> rpdo_pending;
  // The drive.
  Drive drive = Drive::switch_on_disabled;
  std::uint16_t controlword = 0;
  double position = 0;
  double velocity = 0;  // units/s, as the drive measures it (0x606C)
  double target = 0;    // profile position: where the move goes
  bool moving = false;
  bool acknowledged = false;
  bool limited = false;
  bool took_set_point = false;  // profile position: a new set-point was taken (for set_points())
  bool ignores_set_points = false;
  // Cyclic synchronous position: the straight line from `csp_from` (the set-point taken on the
  // SYNC before) to `csp_demand` (the one taken on the last SYNC), followed over one interpolation
  // period from `csp_since`: the drive's position loop follows its interpolated set-points.
  double csp_from = 0, csp_demand = 0;
  Clock::time_point csp_since{};
  Clock::time_point last_update;

  std::uint32_t get(std::uint16_t index, std::uint8_t sub) const { return od.at(detail::key(index, sub)).value; }
  void set(std::uint16_t index, std::uint8_t sub, std::uint32_t v) { od.at(detail::key(index, sub)).value = v; }
  std::int8_t mode() const { return static_cast<std::int8_t>(get(0x6060, 0)); }
  bool cyclic() const { return drive == Drive::enabled && mode() == 8; }
  // Every way out of a motion: the drive stands where it is, in either mode.
  void hold() {
    moving = false;
    target = csp_from = csp_demand = position;
    velocity = 0;
  }
};

}  // namespace fba::emulators

namespace fba::emulators::detail {

// The node's dictionary after a reset: of its communication (0x1000..0x1FFF, with the PDOs' run-time
// state; the drive is not touched), of its application (the drive's objects and state; the joint
// stays where it is), or of both (a reset of the node, or power-on).
void reset_communication(CanopenArmEmulator::Node& n, const CanopenArmOptions& o);
void reset_application(CanopenArmEmulator::Node& n, const CanopenArmOptions& o);
void reset_dictionary(CanopenArmEmulator::Node& n, const CanopenArmOptions& o);

}  // namespace fba::emulators::detail
