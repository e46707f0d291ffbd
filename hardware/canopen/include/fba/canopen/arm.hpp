// A CANopen arm: one CiA 402 drive per joint, driven as one. The core of the hw.canopen_arm
// driver, without the component around it: joint units (radians, or metres for a prismatic joint)
// scaled to drive counts, every command checked against the joint limits before anything is sent,
// synchronised profile position moves, trajectories in cyclic synchronous position (every drive
// takes its set-point on the same SYNC), and one fault policy: whatever faults (an EMCY, a drive
// fault, a lost heartbeat, a set-point not acknowledged, the line), every joint that can still hear
// is quick-stopped, and the error names the joint, its node and the reason. Master::interrupt() is not a fault: a wait it
// ends throws ArmStopped at once, and whoever interrupted stops the arm (quick_stop_all(), from any
// thread, while the master is interrupted too).
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
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
  // Reaching "operation enabled", and every node's boot-up after the NMT reset of start().
  std::chrono::milliseconds enable_timeout{2000};
  // A drive found in fault at start-up (its error code read from 0x603F and told) is reset only
  // when this allows it; otherwise start() refuses it, naming the drive and the code.
  bool reset_faults = false;
  // The SYNC period: the interpolation period of cyclic synchronous position (0x60C2), and how
  // often a profile position move's SYNC is repeated while the drives' acknowledges are awaited.
  std::chrono::milliseconds sync_period{20};
  // What a person should read of start-up: a drive found in fault and its error code, its reset.
  std::function<void(const std::string&)> notice;
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

  // Start-up, every step for every node: NMT reset communication and its boot-up message (a node
  // that does not boot is named); its device type (0x1000) must be a CiA 402 drive's (low 16 bits
  // 402); a drive in fault has its error code (0x603F) told and is reset only if
  // ArmOptions::reset_faults allows it, else refused naming it and the code. Then its heartbeat
  // period, its software limits from the joint limits, its TPDO1 (statusword, position actual) and
  // TPDO2 (velocity actual) sent on every SYNC, its RPDO1 (controlword, target position) taking
  // effect on the next SYNC, profile position mode (0x6060) set before it is enabled, operational,
  // its heartbeat watched, enabled. Any failure quick-stops every joint and throws ArmStopped.
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
  // Cyclic synchronous position (CiA 402 mode 8), for a trajectory: begin_cyclic() holds every
  // drive where it stands (0x607A its own position), sets the interpolation period (the SYNC
  // period) and switches every drive to the mode. cycle() checks the set-points (LimitError, nothing
  // sent), sends each drive its own (RPDO1, taken on the next SYNC), then one SYNC, and waits at
  // most `timeout` for every drive's PDOs answering it: each drive must be in "operation enabled"
  // and follow its set-point (statusword bit 12). One that does not answer or does not follow
  // quick-stops every joint (ArmStopped naming it): the others are given no further set-point, so
  // none moves on alone. end_cyclic() returns every drive to profile position where it stands.
  void begin_cyclic();
  ArmSample cycle(const std::vector<double>& set_points, std::chrono::milliseconds timeout);
  void end_cyclic();
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
  // The drives' PDOs answering the last SYNC, checked as check_drive() does; with `cyclic`, each
  // must also follow its set-point.
  ArmSample read_sample(bool cyclic);
  // The limit checks of move_to() and cycle(): the targets in counts, or LimitError.
  std::vector<std::int32_t> checked_counts(const std::vector<double>& targets) const;
  void start_up();
  std::int32_t to_counts(std::size_t joint, double value) const;
  double acceleration(std::size_t joint) const;  // units per second squared
  std::vector<double> read_positions();

  Master& master_;
  std::vector<ArmJoint> joints_;
  ArmOptions options_;
  std::vector<cia402::Drive> drives_;
};

}  // namespace fba::canopen
