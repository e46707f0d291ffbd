// A CANopen arm emulator: N CiA 402 drives (one per joint) behind a CanBus, answering NMT, SDO,
// PDO, SYNC, sending heartbeats and EMCY, running the CiA 402 state machine and a simulated motion
// in profile position mode (1) or cyclic synchronous position mode (8). It knows nothing of the
// master in hardware/canopen (it is written from the standards), so the master's tests against it
// test both readings of the standards.
//
// Cyclic synchronous position, as CiA 402 defines it and as the drives do: the position set-point
// (0x607A) that arrived before a SYNC is taken on that SYNC, and the drive's position loop follows
// the straight line from the set-point before to it over one interpolation period (0x60C2),
// reporting "drive follows the command value" (statusword bit 12). The set-points each drive took are kept
// per SYNC (set_points()), so a test sees whether the drives moved in step.
//
// Faults can be injected while it runs: a node falls silent, noise on the line, a drive fault with
// its EMCY, a drive that ignores its set-points, the line closed mid-motion. At start: a node that
// is silent from the start, a drive already in fault, a node that is not a CiA 402 drive.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "fba/can/bus.hpp"
#include "fba/can/frame_socket_bus.hpp"
#include "fba/can/slcan_adapter.hpp"

namespace fba::emulators {

struct CanopenArmOptions {
  std::vector<int> nodes{1, 2, 3, 4, 5, 6};
  std::uint16_t heartbeat_ms = 100;         // 0x1017 after a reset; 0 = no heartbeat
  std::int32_t min_position = -10'000'000;  // 0x607D software limits after a reset
  std::int32_t max_position = 10'000'000;
  std::uint32_t profile_velocity = 100'000;  // 0x6081 after a reset, units/s
  std::map<int, std::uint16_t> fault_at_start;   // node -> error code: in fault from power-on (0x603F)
  std::map<int, std::int32_t> position_at_start;  // node -> where its joint stands at power-on, drive units (else 0)
  std::map<int, std::uint32_t> device_type;      // node -> 0x1000 (default 0x00020192: a CiA 402 servo drive)
  std::vector<int> silent;                       // nodes that never answer (not on the bus)
};

// The set-points the drives took on one SYNC, in node order: (node, 0x607A in drive units).
struct SyncSetPoints {
  std::uint64_t sync = 0;  // the SYNC's number, from 1
  std::chrono::steady_clock::time_point when;  // when it was heard, to order it against another device's records
  std::vector<std::pair<int, std::int32_t>> set_points;
  std::int8_t mode = 0;  // 8: cyclic synchronous position; 1: profile position (new set-points only)
};

class CanopenArmEmulator {
 public:
  // `make_noise` puts a burst of noise on the line (see noise_for); inject_garbage() calls it from
  // run()'s thread, between frames. Without it, inject_garbage() does nothing.
  CanopenArmEmulator(can::CanBus& bus, CanopenArmOptions options, std::function<void()> make_noise = {});
  ~CanopenArmEmulator();

  // Sends every node's boot-up message, then answers the bus until stop() or the line is gone.
  // Returns why it ended: "stopped", "disconnected (fault injection)", or the line's error.
  std::string run();
  void stop() { stop_ = true; }

  // Fault injection, safe from any thread; acted on by run() within a few milliseconds.
  void silence(int node);                           // answers nothing and sends no heartbeat from now on
  void inject_garbage();                            // one burst of line noise
  void inject_fault(int node, std::uint16_t code);  // the drive faults and sends EMCY `code`
  void reboot(int node);                            // a power glitch: defaults again, boot-up, pre-operational
  void disconnect();                                // closes the line, as a pulled cable
  // The drive keeps answering (SDO, heartbeat, PDOs) but takes no set-point: no acknowledge in
  // profile position, and in cyclic synchronous position it holds and clears "follows the command".
  void ignore_set_points(int node);

  // For tests: a node's actual position and controlword-driven state bits.
  std::int32_t position(int node) const;
  std::uint16_t statusword(int node) const;
  // How many SDO downloads (writes) the node has heard: a driver's commands.
  std::uint64_t sdo_downloads(int node) const;
  std::uint64_t syncs_seen() const { return syncs_; }
  // Whether run() has sent the nodes' power-on boot-up messages.
  bool started() const { return started_; }
  // Whether silence(node) has taken effect.
  bool silent(int node) const;
  // The frames it heard, oldest first (the last kHeardKept): the order in which a driver's requests
  // reached the drives.
  static constexpr std::size_t kHeardKept = 4096;
  std::vector<can::Frame> heard() const;
  // When each of heard()'s frames was heard, in the same order.
  std::vector<std::chrono::steady_clock::time_point> heard_at() const;
  // The set-points taken, per SYNC on which any drive took one, oldest first (the last kHeardKept).
  std::vector<SyncSetPoints> set_points() const;

  struct Node;

 private:
  void handle(const can::Frame& frame);
  void handle_nmt(const can::Frame& frame);
  void handle_sync();
  void handle_sdo(Node& n, int id, const can::Frame& frame);
  void handle_rpdo(Node& n, const can::Frame& frame);
  void send(const can::Frame& frame);
  void update(std::chrono::steady_clock::time_point now);
  Node& node(int id) const;

  can::CanBus& bus_;
  CanopenArmOptions options_;
  std::function<void()> make_noise_;
  std::map<int, std::unique_ptr<Node>> nodes_;
  mutable std::mutex mutex_;  // guards the nodes and the requests below
  std::vector<std::function<void()>> requests_;
  std::deque<can::Frame> heard_;
  std::deque<std::chrono::steady_clock::time_point> heard_at_;
  std::deque<SyncSetPoints> set_points_;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> syncs_{0};
  std::atomic<bool> started_{false};
  bool disconnect_ = false;
};

// Noise for each transport: on SLCAN, lines that are not frames (bad hex, a length of 9, the wrong
// number of digits, control bytes, an overlong line, a BEL), each ended by a CR as a real adapter's
// would be after a glitch, so the frames after them still arrive; on a socketpair, records of the
// wrong size and a frame with a length of 12.
std::function<void()> noise_for(can::slcan::SlcanAdapter& adapter);
std::function<void()> noise_for(can::FrameSocketBus& bus);

}  // namespace fba::emulators
