// CiA 402 (drives and motion control) on a CANopen master: the drive state machine driven through
// the controlword (0x6040) and read from the statusword (0x6041), the mode of operation, profile
// position moves, quick stop and fault reset. Every wait has a timeout and ends early, with the
// reason, when the drive faults, sends an EMCY, or falls silent. A drive in fault is reset only
// when the caller says so: a fault is the drive's news, and its error code (0x603F) is named.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

#include "fba/canopen/master.hpp"

namespace fba::canopen::cia402 {

namespace od {
constexpr std::uint16_t kErrorCode = 0x603F;
constexpr std::uint16_t kControlword = 0x6040;
constexpr std::uint16_t kStatusword = 0x6041;
constexpr std::uint16_t kModesOfOperation = 0x6060;
constexpr std::uint16_t kModesOfOperationDisplay = 0x6061;
constexpr std::uint16_t kPositionActual = 0x6064;
constexpr std::uint16_t kVelocityActual = 0x606C;
constexpr std::uint16_t kTargetPosition = 0x607A;
constexpr std::uint16_t kSoftwarePositionLimit = 0x607D;  // sub 1 min, sub 2 max
constexpr std::uint16_t kInterpolationPeriod = 0x60C2;    // sub 1 value, sub 2 exponent (value * 10^exponent s)
constexpr std::uint16_t kProfileVelocity = 0x6081;
constexpr std::uint16_t kProfileAcceleration = 0x6083;
constexpr std::uint16_t kProfileDeceleration = 0x6084;
}  // namespace od

// Controlword commands (the low bits) and flags.
namespace cw {
constexpr std::uint16_t kShutdown = 0x0006;
constexpr std::uint16_t kSwitchOn = 0x0007;
constexpr std::uint16_t kEnableOperation = 0x000F;
constexpr std::uint16_t kQuickStop = 0x0002;
constexpr std::uint16_t kDisableVoltage = 0x0000;
constexpr std::uint16_t kFaultReset = 0x0080;   // acts on the rising edge
constexpr std::uint16_t kNewSetPoint = 0x0010;  // profile position: bit 4
constexpr std::uint16_t kChangeImmediately = 0x0020;
constexpr std::uint16_t kRelative = 0x0040;
constexpr std::uint16_t kHalt = 0x0100;
}  // namespace cw

// Statusword flags beside the state bits.
namespace sw {
constexpr std::uint16_t kWarning = 0x0080;
constexpr std::uint16_t kRemote = 0x0200;
constexpr std::uint16_t kTargetReached = 0x0400;
constexpr std::uint16_t kInternalLimit = 0x0800;
constexpr std::uint16_t kSetPointAcknowledge = 0x1000;  // profile position
constexpr std::uint16_t kFollowsCommand = 0x1000;       // cyclic synchronous position: the drive follows the set-points
constexpr std::uint16_t kFollowingError = 0x2000;
}  // namespace sw

constexpr std::int8_t kProfilePosition = 1;
constexpr std::int8_t kCyclicSynchronousPosition = 8;

// 0x1000 of a CiA 402 device: its low 16 bits are the device profile, 402.
constexpr std::uint16_t kDeviceProfile = 402;

enum class State {
  not_ready_to_switch_on,
  switch_on_disabled,
  ready_to_switch_on,
  switched_on,
  operation_enabled,
  quick_stop_active,
  fault_reaction_active,
  fault,
};

// The state a statusword shows (masks 0x4F / 0x6F of CiA 402).
State decode(std::uint16_t statusword);
// The statusword bits (0x6F mask) of a state: what a drive reports in it.
std::uint16_t state_bits(State state);
std::string to_string(State state);

// The drive is in fault and was not to be reset: its node and error code (0x603F).
class DriveFault : public Error {
 public:
  DriveFault(int node_, std::uint16_t code_, const std::string& what) : Error(what), node(node_), code(code_) {}
  int node;
  std::uint16_t code;
};

struct DriveOptions {
  std::chrono::milliseconds poll_period{5};  // between statusword reads while waiting
};

class Drive {
 public:
  Drive(Master& master, int node, DriveOptions options = {});

  int node() const { return node_; }
  std::uint16_t statusword();
  State state() { return decode(statusword()); }
  std::int32_t position();
  // 0x603F: the code of the drive's last fault (0 if none).
  std::uint16_t error_code();

  // Walks the state machine to "operation enabled" from wherever the drive is. A drive in fault
  // throws DriveFault with its error code, unless `reset_fault`: then the fault is reset once (a
  // fault that comes back throws). Returns the error code of the fault it reset, 0 if none. Throws
  // Error naming the node, the state it stuck in and the statusword. Set the mode of operation
  // first (set_mode): CiA 402 asks for it before "operation enabled".
  std::uint16_t enable(std::chrono::milliseconds timeout, bool reset_fault = false);
  // Sets the mode of operation (0x6060) and checks that the drive shows it (0x6061).
  void set_mode(std::int8_t mode);
  // Profile position mode (set_mode) with the given velocity and acceleration (drive units).
  void set_profile(std::uint32_t velocity, std::uint32_t acceleration);
  // Starts a profile position move: target, new set-point, waits for the acknowledge, clears it.
  void start_move(std::int32_t target, std::chrono::milliseconds timeout, bool relative = false);
  bool target_reached();
  // start_move, then waits for "target reached". Throws NodeFault on a fault, EMCY or lost
  // heartbeat meanwhile, Error when the drive leaves "operation enabled" or the time runs out.
  void move_to(std::int32_t target, std::chrono::milliseconds timeout);
  // Quick stop: the drive decelerates and holds in "quick stop active".
  void quick_stop();
  // Fault reset (a rising edge of bit 7); waits until the drive has left "fault" (to "switch on
  // disabled"); throws Error if it stays in fault.
  void fault_reset(std::chrono::milliseconds timeout);
  void disable();

 private:
  void controlword(std::uint16_t value);
  // Polls the statusword until `done` holds, checking the node's faults; throws on timeout with `what`.
  std::uint16_t wait(const std::function<bool(std::uint16_t)>& done, std::chrono::milliseconds timeout,
                     const std::string& what);

  Master& master_;
  int node_;
  DriveOptions options_;
};

}  // namespace fba::canopen::cia402
