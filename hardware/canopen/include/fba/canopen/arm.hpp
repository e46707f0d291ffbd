// A CANopen arm: one CiA 402 drive per joint, driven as one. The core of the hw.canopen_arm
// driver, without the component around it: joint units (radians, or metres for a prismatic joint)
// scaled to drive counts, every command checked against the joint limits before anything is sent,
// synchronised profile position moves, and one fault policy: whatever faults (an EMCY, a drive
// fault, a lost heartbeat, the line), every joint that can still hear is quick-stopped, and the
// error names the joint, its node and the reason. Master::interrupt() is not a fault: a wait it
// ends throws ArmStopped at once, and whoever interrupted stops the arm (quick_stop_all(), from any
// thread, while the master is interrupted too).
#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "fba/canopen/cia402.hpp"
#include "fba/canopen/master.hpp"

namespace fba::canopen {

struct ArmJoint {
  std::string name;        // as in the URDF, for messages
  int node = 0;            // the drive's CANopen node id
  double counts_per_unit;  // drive position units per radian (or metre)
  std::int32_t zero = 0;   // the drive's position at joint position 0
  double lower;            // joint limits, radians (or metres)
  double upper;
  double max_velocity;          // radians (metres) per second, > 0
  double max_acceleration = 0;  // radians (metres) per second squared; 0: ten times max_velocity per second
};

// The arm as its drives' PDOs report it, answering one SYNC.
struct ArmSample {
  std::vector<double> positions;   // joint units (0x6064 through the scale and zero)
  std::vector<double> velocities;  // joint units per second (0x606C)
  bool reached = false;            // every drive reports "target reached" (statusword bit 10)
};

struct ArmOptions {
  std::uint16_t heartbeat_ms = 50;  // written to each drive's 0x1017
  std::chrono::milliseconds heartbeat_timeout{200};
  std::chrono::milliseconds enable_timeout{2000};
};

// A command refused before it left the process: the joint, the value and the limit it breaks.
class LimitError : public Error {
 public:
  using Error::Error;
};

// The arm was stopped because something faulted; the message says what, and whether every quick
// stop went out.
class ArmStopped : public Error {
 public:
  ArmStopped(int node, const std::string& what) : Error(what), node(node) {}
  int node;  // the node that faulted; 0 for the line itself
};

class CanopenArm {
 public:
  // Throws std::invalid_argument for a configuration that cannot be right (no joints, a node id
  // used twice, limits in the wrong order, a zero scale or velocity).
  CanopenArm(Master& master, std::vector<ArmJoint> joints, ArmOptions options = {});

  const std::vector<ArmJoint>& joints() const { return joints_; }

  // Every node operational, its heartbeat watched, its software limits set from the joint limits,
  // its TPDO1 (statusword, position actual) and TPDO2 (velocity actual) sent on every SYNC, its
  // RPDO1 (controlword, target position) taking effect on the next SYNC, its drive enabled in
  // profile position mode.
  void start();
  // Checks every target (count, finite, within limits, representable in counts) and `speed`
  // (0 < speed <= 1 of the joints' maximum velocities and accelerations) and throws LimitError with
  // nothing sent if one fails; then starts one move in which every joint starts, accelerates and
  // arrives together. Returns the move's planned duration, seconds.
  double move_to(const std::vector<double>& targets, double speed = 1.0);
  // Whether every joint has reached its target. Throws ArmStopped, after quick-stopping every
  // joint, if a drive faulted, left "operation enabled", sent an EMCY or fell silent.
  bool reached();
  // Sends SYNC and waits at most `timeout` for every drive's TPDOs answering it. Throws ArmStopped,
  // after quick-stopping every joint, as reached() does, and when a drive does not answer in time.
  ArmSample sample(std::chrono::milliseconds timeout);
  // move_to, then waits for reached() at most `timeout` (ArmStopped on a fault or on the timeout).
  void move_and_wait(const std::vector<double>& targets, double speed, std::chrono::milliseconds timeout);
  // Processes the bus's traffic (heartbeats, EMCY, PDOs) for `duration`; a fault or an interrupt on
  // the way throws ArmStopped after quick-stopping every joint, as everywhere.
  void wait(std::chrono::milliseconds duration);
  // Joint positions from the drives' actual positions (ArmStopped if a drive cannot be read).
  std::vector<double> positions();
  // Sends quick stop to every joint at once (every request before any answer is awaited, so one
  // silent drive does not hold back the others), then waits one SDO timeout for the confirmations.
  // Returns the joints that did not confirm, each with its node and why (empty when every joint
  // did). Safe from another thread while one drives the arm, and while the master is interrupted.
  std::vector<std::string> quick_stop_all();

 private:
  template <class F>
  auto guarded(F&& f) -> decltype(f());
  // Sends SYNC and waits for every drive's TPDO1 and TPDO2 answering it; throws (for guarded()) on
  // a fault or when one does not answer within `timeout`. Every SYNC goes through here, so no answer
  // to an earlier one is still on its way to be taken for the answer to the next.
  void sync(std::chrono::milliseconds timeout);
  // Throws (for guarded()) when a drive has faulted or is not in "operation enabled".
  void check_drive(std::size_t joint, std::uint16_t statusword);
  std::int32_t to_counts(std::size_t joint, double value) const;
  double acceleration(std::size_t joint) const;  // units per second squared
  std::vector<double> read_positions();

  Master& master_;
  std::vector<ArmJoint> joints_;
  ArmOptions options_;
  std::vector<cia402::Drive> drives_;
};

}  // namespace fba::canopen
