#include "fba/emulators/canopen_arm.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>

#include "node.hpp"

namespace fba::emulators {

using namespace detail;  // the drive's codes and states (node.hpp)

namespace {

std::uint16_t statusword(const CanopenArmEmulator::Node& n) {
  std::uint16_t s = static_cast<std::uint16_t>(n.drive) | 0x0200;                    // remote: controlled over the bus
  if (n.drive != Drive::switch_on_disabled && n.drive != Drive::fault) s |= 0x0010;  // voltage enabled
  if (n.limited) s |= 0x0800;                                                        // internal limit active
  if (n.mode() == 8) {
    if (n.position == n.csp_demand) s |= 0x0400;                 // (reserved in CSP) at the set-point
    if (n.cyclic() && !n.ignores_set_points) s |= 0x1000;        // drive follows the command value
  } else {
    if (!n.moving) s |= 0x0400;         // target reached
    if (n.acknowledged) s |= 0x1000;    // set-point acknowledge
  }
  return s;
}

double interpolation_period_s(const CanopenArmEmulator::Node& n) {
  return static_cast<double>(n.get(0x60C2, 1)) * std::pow(10.0, static_cast<std::int8_t>(n.get(0x60C2, 2)));
}

// The objects the drive computes, brought up to date before anything reads them.
void refresh(CanopenArmEmulator::Node& n) {
  n.set(0x6041, 0, statusword(n));
  n.set(0x6061, 0, n.get(0x6060, 0));
  n.set(0x6064, 0, static_cast<std::uint32_t>(static_cast<std::int32_t>(std::lround(n.position))));
  n.set(0x606C, 0, static_cast<std::uint32_t>(static_cast<std::int32_t>(std::lround(n.velocity))));
}

std::uint8_t error_register_for(std::uint16_t code) {
  std::uint8_t reg = 0x01;  // generic
  switch (code >> 12) {
    case 0x2:
      reg |= 0x02;
      break;  // current
    case 0x3:
      reg |= 0x04;
      break;  // voltage
    case 0x4:
      reg |= 0x08;
      break;  // temperature
    case 0x8:
      reg |= (code >> 8) == 0x81 ? 0x10 : 0x20;
      break;  // communication, or device profile
    default:
      break;
  }
  return reg;
}

can::Frame emcy_frame(int id, std::uint16_t code, std::uint8_t reg) {
  return can::make_frame(kEmcy + static_cast<std::uint32_t>(id),
                         {static_cast<std::uint8_t>(code), static_cast<std::uint8_t>(code >> 8), reg, 0, 0, 0, 0, 0});
}

can::Frame sdo_abort(int id, std::uint16_t index, std::uint8_t sub, std::uint32_t code) {
  return can::make_frame(kSdoTx + static_cast<std::uint32_t>(id),
                         {0x80, static_cast<std::uint8_t>(index), static_cast<std::uint8_t>(index >> 8), sub,
                          static_cast<std::uint8_t>(code), static_cast<std::uint8_t>(code >> 8),
                          static_cast<std::uint8_t>(code >> 16), static_cast<std::uint8_t>(code >> 24)});
}

bool pdo_valid(const CanopenArmEmulator::Node& n, std::uint16_t communication) {
  return !(n.get(communication, 1) & 0x80000000U);
}

}  // namespace

CanopenArmEmulator::CanopenArmEmulator(can::CanBus& bus, CanopenArmOptions options, std::function<void()> make_noise)
    : bus_(bus), options_(std::move(options)), make_noise_(std::move(make_noise)) {
  for (int id : options_.nodes) {
    if (id < 1 || id > 127)
      throw std::invalid_argument(fmt::format("CANopen arm emulator: node id {} is not 1..127", id));
    if (nodes_.count(id))
      throw std::invalid_argument(fmt::format("CANopen arm emulator: node id {} is given twice", id));
    auto n = std::make_unique<Node>();
    n->id = id;
    reset_dictionary(*n, options_);
    nodes_[id] = std::move(n);
  }
  if (nodes_.empty()) throw std::invalid_argument("CANopen arm emulator: no node ids given");
  for (const auto& [id, code] : options_.fault_at_start) {  // in fault from power-on: no EMCY heard yet
    Node& n = node(id);
    n.drive = Drive::fault;
    n.set(0x603F, 0, code);
    n.set(0x1001, 0, error_register_for(code));
  }
  for (const auto& [id, position] : options_.position_at_start) node(id).position = position;
  for (const auto& [id, type] : options_.device_type) node(id);  // an unknown node is refused here
  for (int id : options_.silent) node(id).silent = true;
}

CanopenArmEmulator::~CanopenArmEmulator() = default;

CanopenArmEmulator::Node& CanopenArmEmulator::node(int id) const {
  const auto it = nodes_.find(id);
  if (it == nodes_.end()) throw std::invalid_argument(fmt::format("CANopen arm emulator: there is no node {}", id));
  return *it->second;
}

void CanopenArmEmulator::send(const can::Frame& frame) { bus_.send(frame); }

void CanopenArmEmulator::silence(int id) {
  std::lock_guard lock(mutex_);
  node(id);  // throws for an unknown id, in the caller's thread
  requests_.push_back([this, id] { node(id).silent = true; });
}

void CanopenArmEmulator::inject_garbage() {
  std::lock_guard lock(mutex_);
  requests_.push_back([this] {
    if (make_noise_) make_noise_();
  });
}

void CanopenArmEmulator::inject_fault(int id, std::uint16_t code) {
  std::lock_guard lock(mutex_);
  node(id);
  requests_.push_back([this, id, code] {
    Node& n = node(id);
    n.drive = Drive::fault;
    n.hold();
    n.set(0x603F, 0, code);
    n.set(0x1001, 0, error_register_for(code));
    if (!n.silent) send(emcy_frame(id, code, error_register_for(code)));
  });
}

void CanopenArmEmulator::reboot(int id) {
  std::lock_guard lock(mutex_);
  node(id);
  requests_.push_back([this, id] {
    Node& n = node(id);
    reset_dictionary(n, options_);  // the position stays: the joint did not move
    n.nmt = kPreOperational;
    n.last_heartbeat = Clock::now();
    if (!n.silent) send(can::make_frame(kHeartbeat + static_cast<std::uint32_t>(id), {0x00}));
  });
}

void CanopenArmEmulator::disconnect() {
  std::lock_guard lock(mutex_);
  requests_.push_back([this] { disconnect_ = true; });
}

void CanopenArmEmulator::ignore_set_points(int id) {
  std::lock_guard lock(mutex_);
  node(id);
  requests_.push_back([this, id] { node(id).ignores_set_points = true; });
}

std::vector<SyncSetPoints> CanopenArmEmulator::set_points() const {
  std::lock_guard lock(mutex_);
  return {set_points_.begin(), set_points_.end()};
}

std::int32_t CanopenArmEmulator::position(int id) const {
  std::lock_guard lock(mutex_);
  return static_cast<std::int32_t>(std::lround(node(id).position));
}

std::uint16_t CanopenArmEmulator::statusword(int id) const {
  std::lock_guard lock(mutex_);
  return fba::emulators::statusword(node(id));
}

std::uint64_t CanopenArmEmulator::sdo_downloads(int id) const {
  std::lock_guard lock(mutex_);
  return node(id).sdo_downloads;
}

bool CanopenArmEmulator::silent(int id) const {
  std::lock_guard lock(mutex_);
  return node(id).silent;
}

std::vector<can::Frame> CanopenArmEmulator::heard() const {
  std::lock_guard lock(mutex_);
  return {heard_.begin(), heard_.end()};
}

std::vector<Clock::time_point> CanopenArmEmulator::heard_at() const {
  std::lock_guard lock(mutex_);
  return {heard_at_.begin(), heard_at_.end()};
}

std::string CanopenArmEmulator::run() {
  try {
    {
      std::lock_guard lock(mutex_);
      const auto now = Clock::now();
      for (auto& [id, n] : nodes_) {
        if (!n->silent) send(can::make_frame(kHeartbeat + static_cast<std::uint32_t>(id), {0x00}));  // boot-up
        n->nmt = kPreOperational;
        n->last_heartbeat = n->last_update = now;
      }
      started_ = true;
    }
    while (!stop_) {
      {
        std::lock_guard lock(mutex_);
        for (auto& request : requests_) request();
        requests_.clear();
        if (disconnect_) {
          bus_.close();
          return "disconnected (fault injection)";
        }
      }
      const auto frame = bus_.receive(std::chrono::milliseconds(2));
      std::lock_guard lock(mutex_);
      if (frame) {
        heard_.push_back(*frame);
        heard_at_.push_back(Clock::now());
        if (heard_.size() > kHeardKept) heard_.pop_front(), heard_at_.pop_front();
        handle(*frame);
      }
      update(Clock::now());
    }
  } catch (const can::BusError& e) {
    return e.what();
  }
  return "stopped";
}

namespace {

// A write through SDO or an RPDO: the checks of CiA 301, then the drive's reaction. Returns an
// abort code, or 0.
std::uint32_t write_object(CanopenArmEmulator::Node& n, std::uint16_t index, std::uint8_t sub, std::uint32_t value,
                           std::size_t size, const std::function<void(const can::Frame&)>& send);

// The commands of the controlword's low bits (CiA 402); no word is two of them.
enum class Command { none, shutdown, switch_on, enable_operation, disable_voltage, quick_stop };

Command command_of(std::uint16_t cw) {
  if ((cw & 0x02) == 0) return Command::disable_voltage;
  if ((cw & 0x06) == 0x02) return Command::quick_stop;
  if ((cw & 0x87) == 0x06) return Command::shutdown;
  if ((cw & 0x8F) == 0x07) return Command::switch_on;
  if ((cw & 0x8F) == 0x0F) return Command::enable_operation;
  return Command::none;
}

// The state machine's transitions on a command, fault reset apart (it has side effects).
struct Transition {
  Drive from;
  Command command;
  Drive to;
};
constexpr Transition kTransitions[] = {
    {Drive::switch_on_disabled, Command::shutdown, Drive::ready},
    {Drive::ready, Command::switch_on, Drive::switched_on},
    {Drive::ready, Command::enable_operation, Drive::enabled},  // transitions 3 and 4 at once, as most drives allow
    {Drive::ready, Command::disable_voltage, Drive::switch_on_disabled},
    {Drive::ready, Command::quick_stop, Drive::switch_on_disabled},
    {Drive::switched_on, Command::enable_operation, Drive::enabled},
    {Drive::switched_on, Command::shutdown, Drive::ready},
    {Drive::switched_on, Command::disable_voltage, Drive::switch_on_disabled},
    {Drive::switched_on, Command::quick_stop, Drive::switch_on_disabled},
    {Drive::enabled, Command::switch_on, Drive::switched_on},
    {Drive::enabled, Command::shutdown, Drive::ready},
    {Drive::enabled, Command::disable_voltage, Drive::switch_on_disabled},
    {Drive::enabled, Command::quick_stop, Drive::quick_stop},
    {Drive::quick_stop, Command::disable_voltage, Drive::switch_on_disabled},
    {Drive::quick_stop, Command::enable_operation, Drive::enabled},  // quick stop option codes 5-8: transition 16
};

void apply_controlword(CanopenArmEmulator::Node& n, std::uint16_t cw,
                       const std::function<void(const can::Frame&)>& send) {
  const std::uint16_t previous = n.controlword;
  n.controlword = cw;
  Drive next = n.drive;
  if (n.drive == Drive::fault) {
    if ((cw & 0x80) && !(previous & 0x80)) {  // fault reset acts on the rising edge
      next = Drive::switch_on_disabled;
      n.set(0x603F, 0, 0);
      n.set(0x1001, 0, 0);
      send(emcy_frame(n.id, 0x0000, 0));  // error reset
    }
  } else {
    const Command command = command_of(cw);
    for (const Transition& t : kTransitions)
      if (t.from == n.drive && t.command == command) next = t.to;
  }
  if (next != Drive::enabled) n.hold();  // every way out of "operation enabled" stops the motion
  n.drive = next;
  if (n.drive != Drive::enabled || n.mode() != 1 || n.ignores_set_points) return;
  // Profile position: a rising edge of bit 4 takes the target (relative with bit 6); bit 5
  // replaces a move in progress, without it a new set-point waits for the current one to end.
  if ((cw & 0x10) && !(previous & 0x10) && (!n.moving || (cw & 0x20))) {
    const auto target = static_cast<double>(static_cast<std::int32_t>(n.get(0x607A, 0)));
    double goal = (cw & 0x40) ? n.target + target : target;
    const auto lo = static_cast<double>(static_cast<std::int32_t>(n.get(0x607D, 1)));
    const auto hi = static_cast<double>(static_cast<std::int32_t>(n.get(0x607D, 2)));
    n.limited = goal < lo || goal > hi;
    goal = std::clamp(goal, lo, hi);
    n.target = goal;
    n.moving = goal != n.position;
    n.acknowledged = true;
    n.took_set_point = true;
  }
  if (!(cw & 0x10)) n.acknowledged = false;
}

std::uint32_t check_mapping(const CanopenArmEmulator::Node& n, std::uint16_t mapping, std::uint32_t count) {
  if (count > 8) return kAbortValue;
  int bits = 0;
  for (std::uint32_t s = 1; s <= count; ++s) {
    const std::uint32_t m = n.get(mapping, static_cast<std::uint8_t>(s));
    bits += static_cast<int>(m & 0xFF);
  }
  return bits > 64 ? kAbortPdoLength : 0;
}

std::uint32_t write_object(CanopenArmEmulator::Node& n, std::uint16_t index, std::uint8_t sub, std::uint32_t value,
                           std::size_t size, const std::function<void(const can::Frame&)>& send) {
  const auto it = n.od.find(key(index, sub));
  if (it == n.od.end()) {
    const auto any = n.od.lower_bound(key(index, 0));
    return any != n.od.end() && (any->first >> 8) == index ? kAbortNoSub : kAbortNoObject;
  }
  Entry& e = it->second;
  if (!e.writable) return kAbortReadOnly;
  if (size != e.size) return kAbortLength;
  const bool rpdo_map = index >= 0x1600 && index <= 0x1603, tpdo_map = index >= 0x1A00 && index <= 0x1A03;
  if (rpdo_map || tpdo_map) {
    const auto communication = static_cast<std::uint16_t>(index - 0x200);  // 0x1400 or 0x1800 + n
    // CiA 301: the mapping changes only while the PDO is invalid, and entries only while sub 0 is 0.
    if (pdo_valid(n, communication) || (sub != 0 && n.get(index, 0) != 0)) return kAbortDeviceState;
    if (sub == 0) {
      if (const std::uint32_t abort = check_mapping(n, index, value)) return abort;
    } else {
      const auto object =
          n.od.find(key(static_cast<std::uint16_t>(value >> 16), static_cast<std::uint8_t>(value >> 8)));
      if (object == n.od.end()) return kAbortNoObject;
      if (!object->second.mappable) return kAbortNotMappable;
      if ((value & 0xFF) != 8u * object->second.size) return kAbortParameters;
      if (rpdo_map && !object->second.writable) return kAbortNotMappable;
    }
  }
  // Profile position and cyclic synchronous position only. A change of mode starts from where the
  // drive stands: no motion carries over, and the first cyclic set-point is its own position.
  if (index == 0x6060) {
    const auto mode = static_cast<std::int8_t>(value);
    if (mode != 1 && mode != 8) return kAbortValue;
    if (mode != n.mode()) n.hold();
  }
  e.value = value;
  if (index == 0x6040) apply_controlword(n, static_cast<std::uint16_t>(value), send);
  return 0;
}

std::vector<std::uint8_t> pdo_bytes(CanopenArmEmulator::Node& n, std::uint16_t mapping) {
  refresh(n);
  std::vector<std::uint8_t> bytes;
  const std::uint32_t count = n.get(mapping, 0);
  for (std::uint32_t s = 1; s <= count; ++s) {
    const std::uint32_t m = n.get(mapping, static_cast<std::uint8_t>(s));
    const std::uint32_t v = n.get(static_cast<std::uint16_t>(m >> 16), static_cast<std::uint8_t>(m >> 8));
    for (std::uint32_t b = 0; b < (m & 0xFF) / 8; ++b) bytes.push_back(static_cast<std::uint8_t>(v >> (8 * b)));
  }
  return bytes;
}

// The frame of TPDO p (its COB-ID from 0x1800 + p), remembered as the last one sent.
can::Frame tpdo_frame(CanopenArmEmulator::Node& n, int p, std::vector<std::uint8_t> bytes) {
  can::Frame f;
  f.id = n.get(static_cast<std::uint16_t>(0x1800 + p), 1) & 0x7FF;
  f.dlc = static_cast<std::uint8_t>(bytes.size());
  std::copy(bytes.begin(), bytes.end(), f.data.begin());
  n.tpdo_last[p] = std::move(bytes);
  return f;
}

void apply_rpdo(CanopenArmEmulator::Node& n, int p, const can::Frame& frame,
                const std::function<void(const can::Frame&)>& send) {
  const auto mapping = static_cast<std::uint16_t>(0x1600 + p);
  const std::uint32_t count = n.get(mapping, 0);
  std::size_t at = 0;
  std::size_t need = 0;
  for (std::uint32_t s = 1; s <= count; ++s) need += (n.get(mapping, static_cast<std::uint8_t>(s)) & 0xFF) / 8;
  if (frame.dlc < need) {
    send(emcy_frame(n.id, 0x8210, 0x11));  // PDO not processed due to length error
    return;
  }
  // The whole PDO is taken in before the drive acts on a controlword in it, as drives do: a
  // new set-point then moves to the target that came in the same PDO, whatever the mapping order.
  std::optional<std::uint32_t> controlword;
  for (std::uint32_t s = 1; s <= count; ++s) {
    const std::uint32_t m = n.get(mapping, static_cast<std::uint8_t>(s));
    const std::size_t bytes = (m & 0xFF) / 8;
    std::uint32_t v = 0;
    for (std::size_t b = 0; b < bytes; ++b) v |= static_cast<std::uint32_t>(frame.data[at + b]) << (8 * b);
    at += bytes;
    if ((m >> 16) == 0x6040)
      controlword = v;
    else
      write_object(n, static_cast<std::uint16_t>(m >> 16), static_cast<std::uint8_t>(m >> 8), v, bytes, send);
  }
  if (controlword) write_object(n, 0x6040, 0, *controlword, 2, send);
}

}  // namespace

// A frame from the bus, by kind: NMT, SYNC, or an SDO request or RPDO to one of the nodes.
void CanopenArmEmulator::handle(const can::Frame& frame) {
  if (frame.extended || frame.rtr) return;
  if (frame.id == kNmt) return handle_nmt(frame);
  if (frame.id == kSync) return handle_sync();
  const int id = static_cast<int>(frame.id & 0x7F);
  const auto it = nodes_.find(id);
  if (it == nodes_.end() || it->second->silent) return;
  Node& n = *it->second;
  const std::uint32_t function = frame.id & 0x780;
  if (function == kSdoRx) return handle_sdo(n, id, frame);
  if (n.nmt != kOperational) return;
  handle_rpdo(n, frame);
}

// NMT: a state change or a reset, for one node or (node 0) all of them.
void CanopenArmEmulator::handle_nmt(const can::Frame& frame) {
  if (frame.dlc != 2) return;
  for (auto& [id, n] : nodes_) {
    if (n->silent || (frame.data[1] != 0 && frame.data[1] != id)) continue;
    switch (frame.data[0]) {
      case 0x01:
        n->nmt = kOperational;
        break;
      case 0x02:
        n->nmt = kStopped;
        break;
      case 0x80:
        n->nmt = kPreOperational;
        break;
      case 0x81:  // reset node: the whole dictionary, and the drive (a fault is cleared)
      case 0x82:  // reset communication: the communication objects only; the drive keeps its state
        if (frame.data[0] == 0x81)
          reset_dictionary(*n, options_);
        else
          reset_communication(*n, options_);
        send(can::make_frame(kHeartbeat + static_cast<std::uint32_t>(id), {0x00}));
        n->nmt = kPreOperational;
        n->last_heartbeat = Clock::now();
        break;
      default:
        break;
    }
  }
}

// SYNC: each operational node applies its pending RPDOs, takes its set-point and sends its due TPDOs.
void CanopenArmEmulator::handle_sync() {
  const auto sender = [this](const can::Frame& f) { send(f); };
  const std::uint64_t sync = ++syncs_;
  const auto now = Clock::now();
  SyncSetPoints taken{sync, now, {}, 0};
  for (auto& [id, n] : nodes_) {
    if (n->silent || n->nmt != kOperational) continue;
    n->took_set_point = false;
    for (int p = 0; p < 4; ++p)
      if (n->rpdo_pending[p]) {
        apply_rpdo(*n, p, *n->rpdo_pending[p], sender);
        n->rpdo_pending[p].reset();
      }
    // Cyclic synchronous position: the set-point that came before this SYNC is taken on it, and
    // the drive follows the straight line from the one before to it over the interpolation
    // period (a SYNC that comes early cuts the line short: the drive is then at the one before).
    if (n->cyclic() && !n->ignores_set_points) {
      const auto lo = static_cast<double>(static_cast<std::int32_t>(n->get(0x607D, 1)));
      const auto hi = static_cast<double>(static_cast<std::int32_t>(n->get(0x607D, 2)));
      const auto demand = static_cast<double>(static_cast<std::int32_t>(n->get(0x607A, 0)));
      n->limited = demand < lo || demand > hi;
      n->csp_from = n->csp_demand;
      n->csp_demand = std::clamp(demand, lo, hi);
      n->csp_since = now;
      taken.mode = 8;
      taken.set_points.emplace_back(id, static_cast<std::int32_t>(n->csp_demand));
    } else if (n->took_set_point) {
      if (taken.mode == 0) taken.mode = 1;
      taken.set_points.emplace_back(id, static_cast<std::int32_t>(n->target));
    }
    for (int p = 0; p < 4; ++p) {
      const auto communication = static_cast<std::uint16_t>(0x1800 + p);
      const std::uint32_t type = n->get(communication, 2);
      if (!pdo_valid(*n, communication) || type > 240) continue;
      auto bytes = pdo_bytes(*n, static_cast<std::uint16_t>(0x1A00 + p));
      const bool due = type == 0 ? bytes != n->tpdo_last[p] : ++n->tpdo_syncs[p] >= static_cast<int>(type);
      if (!due) continue;
      n->tpdo_syncs[p] = 0;
      send(tpdo_frame(*n, p, std::move(bytes)));
    }
  }
  if (!taken.set_points.empty()) {
    set_points_.push_back(std::move(taken));
    if (set_points_.size() > kHeardKept) set_points_.pop_front();
  }
}

// An SDO request to node `id`: an expedited download or upload; anything else is refused.
void CanopenArmEmulator::handle_sdo(Node& n, int id, const can::Frame& frame) {
  const auto sender = [this](const can::Frame& f) { send(f); };
  if (n.nmt == kStopped || frame.dlc != 8) return;
  const std::uint8_t command = frame.data[0];
  const auto index = static_cast<std::uint16_t>(frame.data[1] | frame.data[2] << 8);
  const std::uint8_t sub = frame.data[3];
  const std::uint32_t value =
      static_cast<std::uint32_t>(frame.data[4]) | static_cast<std::uint32_t>(frame.data[5]) << 8 |
      static_cast<std::uint32_t>(frame.data[6]) << 16 | static_cast<std::uint32_t>(frame.data[7]) << 24;
  switch (command >> 5) {
    case 1: {  // initiate download
      ++n.sdo_downloads;
      if (!(command & 0x02)) {
        send(sdo_abort(id, index, sub, kAbortCommand));  // segmented transfers: not offered
        return;
      }
      const std::size_t size = (command & 0x01) ? 4 - ((command >> 2) & 0x03) : 4;
      const std::uint32_t masked = size == 4 ? value : value & ((1U << (8 * size)) - 1);
      if (const std::uint32_t abort = write_object(n, index, sub, masked, size, sender)) {
        send(sdo_abort(id, index, sub, abort));
      } else {
        send(can::make_frame(
            kSdoTx + static_cast<std::uint32_t>(id),
            {0x60, static_cast<std::uint8_t>(index), static_cast<std::uint8_t>(index >> 8), sub, 0, 0, 0, 0}));
      }
      return;
    }
    case 2: {  // initiate upload
      refresh(n);
      const auto entry = n.od.find(key(index, sub));
      if (entry == n.od.end()) {
        const auto any = n.od.lower_bound(key(index, 0));
        send(sdo_abort(id, index, sub,
                       any != n.od.end() && (any->first >> 8) == index ? kAbortNoSub : kAbortNoObject));
        return;
      }
      if (!entry->second.readable) {
        send(sdo_abort(id, index, sub, kAbortWriteOnly));
        return;
      }
      const std::uint32_t v = entry->second.value;
      const int size = entry->second.size;
      send(can::make_frame(
          kSdoTx + static_cast<std::uint32_t>(id),
          {static_cast<std::uint8_t>(0x43 | ((4 - size) << 2)), static_cast<std::uint8_t>(index),
           static_cast<std::uint8_t>(index >> 8), sub, static_cast<std::uint8_t>(v),
           static_cast<std::uint8_t>(size > 1 ? v >> 8 : 0), static_cast<std::uint8_t>(size > 2 ? v >> 16 : 0),
           static_cast<std::uint8_t>(size > 3 ? v >> 24 : 0)}));
      return;
    }
    case 4:
      return;  // the client aborted: nothing in flight to drop
    default:
      send(sdo_abort(id, index, sub, kAbortCommand));
      return;
  }
}

// A frame that may be one of an operational node's RPDOs: applied now, or on the next SYNC.
void CanopenArmEmulator::handle_rpdo(Node& n, const can::Frame& frame) {
  const auto sender = [this](const can::Frame& f) { send(f); };
  for (int p = 0; p < 4; ++p) {
    const auto communication = static_cast<std::uint16_t>(0x1400 + p);
    if (!pdo_valid(n, communication) || frame.id != (n.get(communication, 1) & 0x7FF)) continue;
    if (n.get(communication, 2) <= 240)
      n.rpdo_pending[p] = frame;  // takes effect on the next SYNC
    else
      apply_rpdo(n, p, frame, sender);
  }
}

void CanopenArmEmulator::update(Clock::time_point now) {
  for (auto& [id, n] : nodes_) {
    const double dt = std::chrono::duration<double>(now - n->last_update).count();
    n->last_update = now;
    if (n->cyclic()) {
      const double period = interpolation_period_s(*n);
      const double share = period > 0 ? std::clamp(std::chrono::duration<double>(now - n->csp_since).count() / period, 0.0, 1.0) : 1.0;
      n->position = n->csp_from + (n->csp_demand - n->csp_from) * share;
      n->velocity = share < 1 && period > 0 ? (n->csp_demand - n->csp_from) / period : 0.0;
    } else if (n->drive == Drive::enabled && n->moving && !(n->controlword & 0x0100)) {  // bit 8: halt
      const double speed = static_cast<double>(n->get(0x6081, 0));
      const double step = speed * dt;
      const double left = n->target - n->position;
      if (std::abs(left) <= step) {
        n->position = n->target;
        n->moving = false;
        n->velocity = 0;
      } else {
        n->position += left > 0 ? step : -step;
        n->velocity = left > 0 ? speed : -speed;
      }
    } else {
      n->velocity = 0;
    }
    if (n->silent) continue;
    const std::uint32_t period = n->get(0x1017, 0);
    if (period > 0 && now - n->last_heartbeat >= std::chrono::milliseconds(period)) {
      send(can::make_frame(kHeartbeat + static_cast<std::uint32_t>(id), {n->nmt}));
      n->last_heartbeat = now;
    }
    if (n->nmt != kOperational) continue;
    for (int p = 0; p < 4; ++p) {  // change-driven and timer-driven TPDOs
      const auto communication = static_cast<std::uint16_t>(0x1800 + p);
      if (!pdo_valid(*n, communication) || n->get(communication, 2) < 0xFE || now - n->tpdo_time[p] < kInhibit)
        continue;
      auto bytes = pdo_bytes(*n, static_cast<std::uint16_t>(0x1A00 + p));
      const std::uint32_t timer = n->get(communication, 5);
      if (bytes == n->tpdo_last[p] && (timer == 0 || now - n->tpdo_time[p] < std::chrono::milliseconds(timer)))
        continue;
      send(tpdo_frame(*n, p, std::move(bytes)));
      n->tpdo_time[p] = now;
    }
  }
}

std::function<void()> noise_for(can::slcan::SlcanAdapter& adapter) {
  return [&adapter] {
    const std::string noise = std::string("\x01\x02\xFF~junk\r") + "t1\r" + "tXYZ8\r" + "t12390011223344556677\r" +
                              "t7FF2AB\r" + std::string(100, 'A') + "\r" + "\a" + "\r\n";
    adapter.write_raw({reinterpret_cast<const std::uint8_t*>(noise.data()), noise.size()});
  };
}

std::function<void()> noise_for(can::FrameSocketBus& bus) {
  return [&bus] {
    const std::uint8_t short_record[5] = {1, 2, 3, 4, 5};
    bus.write_raw(short_record);
    std::uint8_t bad_length[16] = {0x81, 0x05, 0, 0, 12};  // a can_frame of id 0x581 claiming 12 data bytes
    bus.write_raw(bad_length);
  };
}

}  // namespace fba::emulators
