#include "fba/canopen/master.hpp"

#include <algorithm>

#include <fmt/format.h>

namespace fba::canopen {

namespace {

// How long a wait may go without checking heartbeats and SYNC.
constexpr std::chrono::milliseconds kTick{5};
// At most this many EMCY records, and EMCY faults, are kept (the first fault is what counts).
constexpr std::size_t kMaxKept = 1000;

std::string object(std::uint16_t index, std::uint8_t sub) { return fmt::format("0x{:04X}:{:02X}", index, sub); }

std::uint32_t le32(const can::Frame& f, int at) {
  return static_cast<std::uint32_t>(f.data[at]) | static_cast<std::uint32_t>(f.data[at + 1]) << 8 |
         static_cast<std::uint32_t>(f.data[at + 2]) << 16 | static_cast<std::uint32_t>(f.data[at + 3]) << 24;
}

}  // namespace

SdoAbort::SdoAbort(int node_, std::uint16_t index_, std::uint8_t sub_, std::uint32_t code_, const std::string& what)
    : Error(what), node(node_), index(index_), sub(sub_), code(code_) {}

std::string Emergency::describe() const {
  return fmt::format("EMCY 0x{:04X} ({}), error register 0x{:02X} ({})", code, emcy_name(code), error_register,
                     error_register_names(error_register));
}

Master::Master(can::CanBus& bus, MasterOptions options) : bus_(bus), options_(options), next_sync_(Clock::now()) {}

void Master::check_node(int node, bool broadcast_allowed) {
  if (node < (broadcast_allowed ? 0 : 1) || node > kMaxNode)
    throw std::invalid_argument(
        fmt::format("CANopen: node id {} is out of range ({}..127)", node, broadcast_allowed ? 0 : 1));
}

void Master::check_size(int node, std::uint16_t index, std::uint8_t sub, std::size_t got, std::size_t expected) {
  if (got != expected)
    throw Error(fmt::format("node {}: object {} has {} bytes, expected {}", node, object(index, sub), got, expected));
}

void Master::send(const can::Frame& frame) {
  if (interrupted_)
    throw Interrupted(fmt::format("{}: not sent: the master was interrupted (the application is stopping)", bus_.name()));
  bus_.send(frame);
}

void Master::nmt(NmtCommand command, int node) {
  check_node(node, true);
  std::lock_guard lock(mutex_);
  if (command == NmtCommand::reset_node || command == NmtCommand::reset_communication) {
    if (node != 0)
      resets_asked_.insert(node);
    else
      for (const auto& [n, state] : states_) resets_asked_.insert(n);
  }
  send(can::make_frame(kNmtId, {static_cast<std::uint8_t>(command), static_cast<std::uint8_t>(node)}));
}

bool Master::known(int node) const { return states_.count(node) != 0; }

bool Master::awaiting_boot(int node) const {
  std::lock_guard lock(mutex_);
  return resets_asked_.count(node) != 0;
}

NmtState Master::state(int node) const {
  std::lock_guard lock(mutex_);
  const auto it = states_.find(node);
  return it == states_.end() ? NmtState::unknown : it->second;
}

void Master::send_sync() {
  std::lock_guard lock(mutex_);
  send(can::make_frame(kSyncId, {}));
}

void Master::watch_heartbeat(int node, std::chrono::milliseconds timeout) {
  check_node(node, false);
  std::lock_guard lock(mutex_);
  heartbeats_[node] = HeartbeatWatch{timeout, Clock::now(), false};
}

std::vector<Fault> Master::faults() const {
  std::lock_guard lock(mutex_);
  return faults_;
}

std::vector<Emergency> Master::emergencies() const {
  std::lock_guard lock(mutex_);
  return emergencies_;
}

void Master::clear_faults(int node) {
  std::lock_guard lock(mutex_);
  std::erase_if(faults_, [node](const Fault& f) { return f.node == node; });
}

void Master::throw_if_faulted(int node) const {
  std::lock_guard lock(mutex_);
  for (const Fault& f : faults_)
    if (f.node == node) throw NodeFault(f);
}

std::uint64_t Master::discarded() const {
  std::lock_guard lock(mutex_);
  return bus_.discarded();
}

std::string Master::last_discard_reason() const {
  std::lock_guard lock(mutex_);
  return bus_.last_discard_reason();
}

std::optional<PdoSample> Master::tpdo(int node, int number) const {
  std::lock_guard lock(mutex_);
  const auto it = tpdos_.find({node, number});
  if (it == tpdos_.end()) return std::nullopt;
  return it->second;
}

void Master::step(Clock::time_point deadline, bool interruptible) {
  if (interruptible && interrupted_)
    throw Interrupted(fmt::format("{}: the wait was interrupted (the application is stopping)", bus_.name()));
  std::lock_guard lock(mutex_);
  auto now = Clock::now();
  auto until = std::min(deadline, now + kTick);
  if (options_.sync_period.count() > 0) until = std::min(until, next_sync_);
  const auto wait =
      std::max(std::chrono::milliseconds(0), std::chrono::duration_cast<std::chrono::milliseconds>(until - now));
  // Everything already waiting is taken in before heartbeats are judged: after a stall of this
  // thread, a heartbeat that arrived in time must not count as missing. (Bounded, so a flooded bus
  // still lets the checks run.)
  for (int n = 0; n < 256; ++n) {
    const auto frame = bus_.receive(n == 0 ? wait : std::chrono::milliseconds(0));
    if (!frame) break;
    dispatch(*frame);
  }
  now = Clock::now();
  if (options_.sync_period.count() > 0 && now >= next_sync_ && !interrupted_) {
    bus_.send(can::make_frame(kSyncId, {}));
    next_sync_ = std::max(next_sync_ + options_.sync_period, now);  // no burst to catch up after a stall
  }
  check_heartbeats(now);
}

void Master::spin_for(std::chrono::milliseconds duration) {
  const auto deadline = Clock::now() + duration;
  do step(deadline);
  while (Clock::now() < deadline);
}

bool Master::spin_until(const std::function<bool()>& done, std::chrono::milliseconds timeout) {
  const auto deadline = Clock::now() + timeout;
  for (;;) {
    if (done()) return true;
    if (Clock::now() >= deadline) return false;
    step(deadline);
  }
}

void Master::check_heartbeats(Clock::time_point now) {
  for (auto& [node, watch] : heartbeats_) {
    if (watch.lost || now - watch.last <= watch.timeout) continue;
    watch.lost = true;
    const auto silent = std::chrono::duration_cast<std::chrono::milliseconds>(now - watch.last);
    faults_.push_back(
        {Fault::Kind::heartbeat_lost, node,
         fmt::format("node {}: heartbeat lost: nothing heard for {} ms (consumer timeout {} ms); last state {}", node,
                     silent.count(), watch.timeout.count(), to_string(state(node)))});
  }
}

void Master::dispatch(const can::Frame& frame) {
  if (frame.extended) return;  // CANopen's predefined connection set is 11-bit
  const std::uint32_t function = frame.id & 0x780;
  const int node = static_cast<int>(frame.id & 0x7F);
  if (node == 0) return;  // NMT and SYNC: other masters' traffic
  if (function == kHeartbeatBase && frame.dlc >= 1 && !frame.rtr) {
    const auto state = static_cast<NmtState>(frame.data[0] & 0x7F);
    if (state == NmtState::boot_up && known(node) && !resets_asked_.erase(node))
      faults_.push_back(
          {Fault::Kind::rebooted, node,
           fmt::format("node {}: rebooted unasked (boot-up message while {}); its drive and PDO configuration are "
                       "back at their defaults",
                       node, to_string(this->state(node)))});
    else if (state == NmtState::boot_up)
      resets_asked_.erase(node);
    // A boot-up message says the node has entered pre-operational (CiA 301).
    states_[node] = state == NmtState::boot_up ? NmtState::pre_operational : state;
    if (auto it = heartbeats_.find(node); it != heartbeats_.end()) {
      it->second.last = Clock::now();
      it->second.lost = false;  // heard again; the fault stays until cleared
    }
  } else if (function == kEmcyBase && frame.dlc == 8) {
    Emergency e{node, static_cast<std::uint16_t>(frame.data[0] | frame.data[1] << 8), frame.data[2], {}};
    std::copy(frame.data.begin() + 3, frame.data.end(), e.vendor.begin());
    // A node that repeats an EMCY without end must not grow the master without end: the oldest go.
    if (emergencies_.size() >= kMaxKept) emergencies_.erase(emergencies_.begin());
    emergencies_.push_back(e);
    if (e.code != 0x0000)  // 0x0000 says an earlier error is reset
      if (faults_.size() < kMaxKept)
        faults_.push_back({Fault::Kind::emergency, node, fmt::format("node {}: {}", node, e.describe())});
  } else if (function == kSdoTxBase && frame.dlc == 8) {
    // To the oldest request of that object still waiting; an answer to a request already given up
    // matches none and is dropped.
    const auto index = static_cast<std::uint16_t>(frame.data[1] | frame.data[2] << 8);
    for (SdoWait* w : sdo_waits_)
      if (w->node == node && w->index == index && w->sub == frame.data[3] && !w->reply) {
        w->reply = frame;
        break;
      }
  } else {
    for (int n = 0; n < 4; ++n)
      if (frame.id == kTpdoBase[n] + static_cast<std::uint32_t>(node)) {
        PdoSample& s = tpdos_[{node, n + 1}];
        s.frame = frame;
        s.time = Clock::now();
        ++s.count;
      }
  }
}

void Master::exchange(std::span<SdoWait> waits, std::span<const can::Frame> requests, bool interruptible) {
  struct Registered {  // the waits leave the list however the exchange ends
    Master& m;
    std::span<SdoWait> waits;
    ~Registered() {
      std::lock_guard lock(m.mutex_);
      for (SdoWait& w : waits) std::erase(m.sdo_waits_, &w);
    }
  } registered{*this, waits};
  {
    std::lock_guard lock(mutex_);
    for (std::size_t i = 0; i < waits.size(); ++i) {
      sdo_waits_.push_back(&waits[i]);
      if (interruptible)
        send(requests[i]);
      else
        bus_.send(requests[i]);
    }
  }
  const auto deadline = Clock::now() + options_.sdo_timeout;
  auto answered = [&] {
    std::lock_guard lock(mutex_);
    return std::all_of(waits.begin(), waits.end(), [](const SdoWait& w) { return w.reply.has_value(); });
  };
  while (!answered() && Clock::now() < deadline) step(deadline, interruptible);
  std::lock_guard lock(mutex_);
  for (const SdoWait& w : waits)
    if (!w.reply)
      bus_.send(can::make_frame(kSdoRxBase + static_cast<std::uint32_t>(w.node),
                                {sdo::kAbort, static_cast<std::uint8_t>(w.index), static_cast<std::uint8_t>(w.index >> 8),
                                 w.sub, 0x00, 0x00, 0x04, 0x05}));  // 0x05040000 SDO protocol timed out
}

std::string Master::no_answer(int node, std::uint16_t index, std::uint8_t sub, const char* what) const {
  std::lock_guard lock(mutex_);
  std::string why = fmt::format("node {}: no answer to the SDO {} of {} within {} ms", node, what, object(index, sub),
                                options_.sdo_timeout.count());
  if (auto it = heartbeats_.find(node); it != heartbeats_.end() && it->second.lost)
    why += " (its heartbeat is lost too)";
  else if (!known(node))
    why += " (nothing has been heard from this node: is it on the bus, with this id?)";
  return why;
}

SdoAbort Master::abort_of(const can::Frame& reply, int node, std::uint16_t index, std::uint8_t sub, const char* what) {
  const std::uint32_t code = le32(reply, 4);
  return SdoAbort(node, index, sub, code,
                  fmt::format("node {}: SDO {} of {} aborted with 0x{:08X} ({})", node, what, object(index, sub), code,
                              sdo_abort_name(code)));
}

can::Frame Master::sdo_exchange(int node, std::uint16_t index, std::uint8_t sub, const can::Frame& request,
                                const char* what) {
  SdoWait wait{node, index, sub, std::nullopt};
  exchange({&wait, 1}, {&request, 1}, true);
  if (!wait.reply) throw SdoTimeout(node, no_answer(node, index, sub, what));
  if (wait.reply->data[0] == sdo::kAbort) throw abort_of(*wait.reply, node, index, sub, what);
  return *wait.reply;
}

std::vector<std::string> Master::download_all(std::span<const SdoWrite> writes) {
  std::vector<SdoWait> waits;
  std::vector<can::Frame> requests;
  std::set<int> nodes;
  for (const SdoWrite& w : writes) {
    check_node(w.node, false);
    if (!nodes.insert(w.node).second)
      throw std::invalid_argument(fmt::format("node {}: given two SDO downloads at once; one at a time", w.node));
    if (w.data.empty() || w.data.size() > 4)
      throw std::invalid_argument(fmt::format("node {}: an expedited SDO download of {} carries 1 to 4 bytes, not {}",
                                              w.node, object(w.index, w.sub), w.data.size()));
    can::Frame request = can::make_frame(
        kSdoRxBase + static_cast<std::uint32_t>(w.node),
        {sdo::expedited(sdo::kDownloadRequest, static_cast<int>(w.data.size())), static_cast<std::uint8_t>(w.index),
         static_cast<std::uint8_t>(w.index >> 8), w.sub, 0, 0, 0, 0});
    std::copy(w.data.begin(), w.data.end(), request.data.begin() + 4);
    waits.push_back({w.node, w.index, w.sub, std::nullopt});
    requests.push_back(request);
  }
  std::vector<std::string> out(writes.size());
  try {
    exchange(waits, requests, false);
  } catch (const std::exception& e) {  // the line is gone: every write not confirmed by then failed with it
    for (std::size_t i = 0; i < waits.size(); ++i)
      if (!waits[i].reply) out[i] = e.what();
  }
  for (std::size_t i = 0; i < waits.size(); ++i) {
    const SdoWait& w = waits[i];
    if (!out[i].empty()) continue;
    if (!w.reply)
      out[i] = no_answer(w.node, w.index, w.sub, "download");
    else if (w.reply->data[0] == sdo::kAbort)
      out[i] = abort_of(*w.reply, w.node, w.index, w.sub, "download").what();
    else if (w.reply->data[0] != sdo::kDownloadResponse)
      out[i] = fmt::format("node {}: the SDO download of {} was answered with command byte 0x{:02X}, expected 0x60",
                           w.node, object(w.index, w.sub), w.reply->data[0]);
  }
  return out;
}

void Master::sdo_download(int node, std::uint16_t index, std::uint8_t sub, std::span<const std::uint8_t> data) {
  check_node(node, false);
  if (data.empty() || data.size() > 4)
    throw std::invalid_argument(fmt::format("node {}: an expedited SDO download of {} carries 1 to 4 bytes, not {}",
                                            node, object(index, sub), data.size()));
  can::Frame request =
      can::make_frame(kSdoRxBase + static_cast<std::uint32_t>(node),
                      {sdo::expedited(sdo::kDownloadRequest, static_cast<int>(data.size())),
                       static_cast<std::uint8_t>(index), static_cast<std::uint8_t>(index >> 8), sub, 0, 0, 0, 0});
  std::copy(data.begin(), data.end(), request.data.begin() + 4);
  const can::Frame reply = sdo_exchange(node, index, sub, request, "download");
  if (reply.data[0] != sdo::kDownloadResponse)
    throw Error(fmt::format("node {}: the SDO download of {} was answered with command byte 0x{:02X}, expected 0x60",
                            node, object(index, sub), reply.data[0]));
}

std::vector<std::uint8_t> Master::sdo_upload(int node, std::uint16_t index, std::uint8_t sub) {
  check_node(node, false);
  const can::Frame request = can::make_frame(
      kSdoRxBase + static_cast<std::uint32_t>(node),
      {sdo::kUploadRequest, static_cast<std::uint8_t>(index), static_cast<std::uint8_t>(index >> 8), sub, 0, 0, 0, 0});
  const can::Frame reply = sdo_exchange(node, index, sub, request, "upload");
  const std::uint8_t command = reply.data[0];
  if ((command & 0xE0) != sdo::kUploadResponse)
    throw Error(fmt::format("node {}: the SDO upload of {} was answered with command byte 0x{:02X}, expected 0x4n",
                            node, object(index, sub), command));
  if (!(command & sdo::kExpedited)) {
    std::lock_guard lock(mutex_);
    bus_.send(can::make_frame(kSdoRxBase + static_cast<std::uint32_t>(node),
                              {sdo::kAbort, static_cast<std::uint8_t>(index), static_cast<std::uint8_t>(index >> 8),
                               sub, 0x01, 0x00, 0x04, 0x05}));  // 0x05040001 command specifier not valid
    throw Error(fmt::format("node {}: object {} is longer than 4 bytes ({} bytes); segmented SDO is not supported",
                            node, object(index, sub), le32(reply, 4)));
  }
  const std::size_t size = (command & sdo::kSizeIndicated) ? 4 - ((command >> 2) & 0x03) : 4;
  return {reply.data.begin() + 4, reply.data.begin() + 4 + static_cast<std::ptrdiff_t>(size)};
}

void Master::configure_pdo(int node, int number, const PdoConfig& config, bool transmit) {
  check_node(node, false);
  const char* kind = transmit ? "TPDO" : "RPDO";
  if (number < 1 || number > 4)
    throw std::invalid_argument(fmt::format("node {}: {} number {} is not 1..4", node, kind, number));
  int bits = 0;
  for (const PdoEntry& e : config.entries) {
    if (e.bits != 8 && e.bits != 16 && e.bits != 32)
      throw std::invalid_argument(fmt::format("node {}: {}{} maps {} with {} bits; 8, 16 or 32 expected", node, kind,
                                              number, object(e.index, e.sub), e.bits));
    bits += e.bits;
  }
  if (bits > 64 || config.entries.size() > 8)
    throw std::invalid_argument(
        fmt::format("node {}: {}{} maps {} bits, at most 64 fit in a frame", node, kind, number, bits));
  const auto n = static_cast<std::uint16_t>(number - 1);
  const std::uint16_t communication = static_cast<std::uint16_t>((transmit ? 0x1800 : 0x1400) + n);
  const std::uint16_t mapping = static_cast<std::uint16_t>((transmit ? 0x1A00 : 0x1600) + n);
  const std::uint32_t cob_id = (transmit ? kTpdoBase[n] : kRpdoBase[n]) + static_cast<std::uint32_t>(node);
  constexpr std::uint32_t kInvalid = 0x80000000U;
  write<std::uint32_t>(node, communication, 1, cob_id | kInvalid);
  write<std::uint8_t>(node, communication, 2, config.transmission_type);
  if (transmit) write<std::uint16_t>(node, communication, 5, config.event_timer_ms);
  write<std::uint8_t>(node, mapping, 0, 0);
  for (std::size_t i = 0; i < config.entries.size(); ++i) {
    const PdoEntry& e = config.entries[i];
    write<std::uint32_t>(node, mapping, static_cast<std::uint8_t>(i + 1),
                         static_cast<std::uint32_t>(e.index) << 16 | static_cast<std::uint32_t>(e.sub) << 8 | e.bits);
  }
  write<std::uint8_t>(node, mapping, 0, static_cast<std::uint8_t>(config.entries.size()));
  write<std::uint32_t>(node, communication, 1, cob_id);
}

void Master::configure_rpdo(int node, int number, const PdoConfig& config) {
  configure_pdo(node, number, config, false);
}
void Master::configure_tpdo(int node, int number, const PdoConfig& config) {
  configure_pdo(node, number, config, true);
}

void Master::send_rpdo(int node, int number, std::span<const std::uint8_t> data) {
  check_node(node, false);
  if (number < 1 || number > 4)
    throw std::invalid_argument(fmt::format("node {}: RPDO number {} is not 1..4", node, number));
  if (data.size() > 8)
    throw std::invalid_argument(fmt::format("node {}: RPDO{} of {} bytes, at most 8", node, number, data.size()));
  can::Frame f;
  f.id = kRpdoBase[number - 1] + static_cast<std::uint32_t>(node);
  f.dlc = static_cast<std::uint8_t>(data.size());
  std::copy(data.begin(), data.end(), f.data.begin());
  std::lock_guard lock(mutex_);
  send(f);
}

}  // namespace fba::canopen
