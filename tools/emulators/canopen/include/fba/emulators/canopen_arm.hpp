// A CANopen arm emulator: N CiA 402 drives (one per joint) behind a CanBus, answering NMT, SDO,
// PDO, SYNC, sending heartbeats and EMCY, running the CiA 402 state machine and a simulated
// profile position motion. It knows nothing of the master in hardware/canopen (it is written from
// the standards), so the master's tests against it test both readings of the standards.
// Faults can be injected while it runs: a node falls silent, noise on the line, a drive fault with
// its EMCY, the line closed mid-motion.
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

  // For tests: a node's actual position and controlword-driven state bits.
  std::int32_t position(int node) const;
  std::uint16_t statusword(int node) const;
  // How many SDO downloads (writes) the node has heard: a driver's commands.
  std::uint64_t sdo_downloads(int node) const;
  std::uint64_t syncs_seen() const { return syncs_; }
  // Whether silence(node) has taken effect.
  bool silent(int node) const;
  // The frames it heard, oldest first (the last kHeardKept): the order in which a driver's requests
  // reached the drives.
  static constexpr std::size_t kHeardKept = 4096;
  std::vector<can::Frame> heard() const;

  struct Node;

 private:
  void handle(const can::Frame& frame);
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
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> syncs_{0};
  bool disconnect_ = false;
};

// Noise for each transport: on SLCAN, lines that are not frames (bad hex, a length of 9, the wrong
// number of digits, control bytes, an overlong line, a BEL), each ended by a CR as a real adapter's
// would be after a glitch, so the frames after them still arrive; on a socketpair, records of the
// wrong size and a frame with a length of 12.
std::function<void()> noise_for(can::slcan::SlcanAdapter& adapter);
std::function<void()> noise_for(can::FrameSocketBus& bus);

}  // namespace fba::emulators
