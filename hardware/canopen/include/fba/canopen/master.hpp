// A CANopen (CiA 301) master on a CanBus: NMT, expedited SDO with timeouts and named abort codes,
// PDO mapping (configured through SDO) and exchange, a SYNC producer, heartbeat consumption and
// EMCY. It has no thread of its own: every call processes the traffic that arrives while it waits
// (heartbeats, EMCY, PDOs), and spin_for() does so when nothing else is asked. Nothing waits longer
// than its timeout. One thread drives the devices; another may stop them meanwhile (interrupt(),
// then download_all()): every call holds the master's lock for one frame or one step of a wait
// (a few milliseconds), so a stop goes out between two of the other thread's steps.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <concepts>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "fba/can/bus.hpp"
#include "fba/canopen/protocol.hpp"

namespace fba::canopen {

using Clock = std::chrono::steady_clock;

// Every CANopen failure; the message names the node and, where there is one, the object.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The node refused an SDO with an abort code: "node 3: SDO upload of 0x2000:00 aborted with
// 0x06020000 (object does not exist in the object dictionary)".
class SdoAbort : public Error {
 public:
  SdoAbort(int node, std::uint16_t index, std::uint8_t sub, std::uint32_t code, const std::string& what);
  int node;
  std::uint16_t index;
  std::uint8_t sub;
  std::uint32_t code;
};

// No SDO answer within the timeout.
class SdoTimeout : public Error {
 public:
  SdoTimeout(int node_, const std::string& what) : Error(what), node(node_) {}
  int node;
};

struct Emergency {
  int node = 0;
  std::uint16_t code = 0;
  std::uint8_t error_register = 0;
  std::array<std::uint8_t, 5> vendor{};
  // "EMCY 0x2310 (continuous over-current), error register 0x03 (generic, current)"
  std::string describe() const;
};

// Something a node did that the application must act on.
struct Fault {
  // rebooted: a boot-up message the master did not ask for (a power glitch, a watchdog reset);
  // the node's drive and PDO configuration are back at their defaults.
  enum class Kind { heartbeat_lost, emergency, rebooted };
  Kind kind;
  int node;
  std::string message;  // names the node and the reason
};

// Master::interrupt() ended a wait: the application is stopping.
class Interrupted : public Error {
 public:
  using Error::Error;
};

// A node reported a fault (or went silent) while the master waited on it.
class NodeFault : public Error {
 public:
  explicit NodeFault(Fault f) : Error(f.message), fault(std::move(f)) {}
  Fault fault;
};

struct PdoEntry {
  std::uint16_t index;
  std::uint8_t sub;
  std::uint8_t bits;  // 8, 16 or 32
};

struct PdoConfig {
  std::vector<PdoEntry> entries;  // at most 64 bits in all
  // 1..240: the PDO goes (TPDO) or takes effect (RPDO) on every n-th SYNC; 0xFE, 0xFF: on change.
  std::uint8_t transmission_type = 0xFF;
  std::uint16_t event_timer_ms = 0;  // TPDO: sent at least this often; 0 = only on change or SYNC
};

struct PdoSample {
  can::Frame frame;
  Clock::time_point time;
  std::uint64_t count = 0;  // how many have arrived
};

// One expedited SDO download of download_all().
struct SdoWrite {
  int node = 0;
  std::uint16_t index = 0;
  std::uint8_t sub = 0;
  std::vector<std::uint8_t> data;  // 1 to 4 bytes
};

struct MasterOptions {
  std::chrono::milliseconds sdo_timeout{200};
  std::chrono::milliseconds sync_period{0};  // 0: no SYNC producer
};

class Master {
 public:
  explicit Master(can::CanBus& bus, MasterOptions options = {});

  can::CanBus& bus() { return bus_; }
  const MasterOptions& options() const { return options_; }

  // NMT: `node` 0 addresses every node.
  void nmt(NmtCommand command, int node);
  // The state from the node's last heartbeat or boot-up message.
  NmtState state(int node) const;
  // Whether the node was sent an NMT reset (node or communication) and its boot-up message has not
  // come yet.
  bool awaiting_boot(int node) const;

  // Expedited SDO (1-4 bytes). Throw SdoAbort, SdoTimeout, or can::BusError if the line is gone.
  // A node answers one SDO at a time, but each node is a server of its own: calls to different
  // nodes may overlap (from different threads).
  void sdo_download(int node, std::uint16_t index, std::uint8_t sub, std::span<const std::uint8_t> data);
  std::vector<std::uint8_t> sdo_upload(int node, std::uint16_t index, std::uint8_t sub);
  template <std::integral T>
  void write(int node, std::uint16_t index, std::uint8_t sub, T value) {
    std::array<std::uint8_t, sizeof(T)> bytes;
    for (std::size_t i = 0; i < sizeof(T); ++i)
      bytes[i] = static_cast<std::uint8_t>(static_cast<std::uint64_t>(value) >> (8 * i));
    sdo_download(node, index, sub, bytes);
  }
  // Throws Error when the node answers with a size other than sizeof(T).
  template <std::integral T>
  T read(int node, std::uint16_t index, std::uint8_t sub) {
    const auto bytes = sdo_upload(node, index, sub);
    check_size(node, index, sub, bytes.size(), sizeof(T));
    std::uint64_t v = 0;
    for (std::size_t i = 0; i < sizeof(T); ++i) v |= static_cast<std::uint64_t>(bytes[i]) << (8 * i);
    return static_cast<T>(v);
  }

  // Expedited SDO downloads to several nodes (one each) at once, the way a stop goes out: every
  // request is sent before any answer is awaited, then one wait of the SDO timeout for all the
  // answers, so a silent node costs one timeout, not one for each node behind it. Returns, per
  // write, "" when the node confirmed it, else why not (an abort by name, no answer, the line
  // gone). Runs while interrupted too: it is what the stop sends.
  std::vector<std::string> download_all(std::span<const SdoWrite> writes);

  // PDO mapping through SDO, the CiA 301 way: invalidate the PDO, set its transmission type, clear
  // the mapping, write the entries, set their count, validate it on its default COB-ID.
  // `number` is 1..4. The node must be pre-operational or operational.
  void configure_rpdo(int node, int number, const PdoConfig& config);
  void configure_tpdo(int node, int number, const PdoConfig& config);
  // Sends RPDO `number` to `node` with the given bytes (the node applies it when operational).
  void send_rpdo(int node, int number, std::span<const std::uint8_t> data);
  // The last TPDO `number` from `node`, if any arrived.
  std::optional<PdoSample> tpdo(int node, int number) const;

  void send_sync();

  // Heartbeat consumer: from now on, `node` must be heard at least every `timeout`, or a
  // heartbeat_lost fault names it.
  void watch_heartbeat(int node, std::chrono::milliseconds timeout);

  // Processes traffic (and produces SYNC, checks heartbeats) for `duration`.
  void spin_for(std::chrono::milliseconds duration);
  // Processes traffic until `done()` or the timeout; returns whether done() became true.
  bool spin_until(const std::function<bool()>& done, std::chrono::milliseconds timeout);

  // Faults recorded so far, oldest first; a node's faults stay until clear_faults(node). EMCY
  // faults and records stop at 1000 (the records keep the latest), so a babbling node cannot
  // exhaust memory.
  std::vector<Fault> faults() const;
  void clear_faults(int node);
  // Throws NodeFault with the node's first fault, if it has one.
  void throw_if_faulted(int node) const;
  std::vector<Emergency> emergencies() const;

  // The bus's skipped input (CanBus::discarded, last_discard_reason), read under the master's lock.
  std::uint64_t discarded() const;
  std::string last_discard_reason() const;

  // From any thread: every wait in progress or to come throws Interrupted at its next step (within
  // a few milliseconds), and nothing more is sent but download_all()'s requests, until resume():
  // the thread that drives the devices can no longer undo a stop.
  void interrupt() { interrupted_ = true; }
  void resume() { interrupted_ = false; }
  bool interrupted() const { return interrupted_; }

 private:
  struct HeartbeatWatch {
    std::chrono::milliseconds timeout;
    Clock::time_point last;
    bool lost = false;
  };

  // An SDO request in flight, and its answer once dispatch() has matched one to it.
  struct SdoWait {
    int node;
    std::uint16_t index;
    std::uint8_t sub;
    std::optional<can::Frame> reply;
  };

  // Waits for one frame until `deadline` (at most until the next SYNC or heartbeat check) and
  // processes it; then produces a due SYNC and checks heartbeats. An interruptible step throws
  // Interrupted once interrupt() was called.
  void step(Clock::time_point deadline, bool interruptible = true);
  void dispatch(const can::Frame& frame);
  void check_heartbeats(Clock::time_point now);
  bool known(int node) const;
  // Sends a frame, unless interrupted (then Interrupted).
  void send(const can::Frame& frame);
  // Sends every requests[i] before awaiting any answer, then waits until each has its answer in
  // waits[i].reply or the SDO timeout passes; a request left unanswered is aborted on the line, as
  // CiA 301 asks of a client that gives up. An interruptible exchange ends with Interrupted once
  // interrupt() was called; the other goes on regardless.
  void exchange(std::span<SdoWait> waits, std::span<const can::Frame> requests, bool interruptible);
  can::Frame sdo_exchange(int node, std::uint16_t index, std::uint8_t sub, const can::Frame& request, const char* what);
  std::string no_answer(int node, std::uint16_t index, std::uint8_t sub, const char* what) const;
  static SdoAbort abort_of(const can::Frame& reply, int node, std::uint16_t index, std::uint8_t sub, const char* what);
  void configure_pdo(int node, int number, const PdoConfig& config, bool transmit);
  static void check_node(int node, bool broadcast_allowed);
  static void check_size(int node, std::uint16_t index, std::uint8_t sub, std::size_t got, std::size_t expected);

  can::CanBus& bus_;
  MasterOptions options_;
  std::map<int, NmtState> states_;
  std::set<int> resets_asked_;  // nodes whose next boot-up the master asked for (NMT reset)
  std::map<int, HeartbeatWatch> heartbeats_;
  std::map<std::pair<int, int>, PdoSample> tpdos_;
  std::vector<Fault> faults_;
  std::vector<Emergency> emergencies_;
  Clock::time_point next_sync_;
  std::vector<SdoWait*> sdo_waits_;  // the SDO requests in flight, oldest first
  std::atomic<bool> interrupted_{false};
  // Held for one frame, one step of a wait, or one look at the state; recursive, as a wait's
  // condition reads the state through the public calls.
  mutable std::recursive_mutex mutex_;
};

}  // namespace fba::canopen
