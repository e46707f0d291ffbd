#include "fba/canopen/arm.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <set>

#include <fmt/format.h>
#include <fmt/ranges.h>

namespace fba::canopen {

namespace {

std::string joint_name(const ArmJoint& j) { return fmt::format("joint '{}' (node {})", j.name, j.node); }

// A joint's drive is not where a move needs it; guarded() turns it into ArmStopped for that node.
class JointFailure : public Error {
 public:
  JointFailure(int node, const std::string& what) : Error(what), node(node) {}
  int node;
};

}  // namespace

CanopenArm::CanopenArm(Master& master, std::vector<ArmJoint> joints, ArmOptions options)
    : master_(master), joints_(std::move(joints)), options_(options) {
  if (joints_.empty()) throw std::invalid_argument("CANopen arm: no joints given");
  std::set<int> nodes;
  for (const ArmJoint& j : joints_) {
    if (j.node < 1 || j.node > kMaxNode)
      throw std::invalid_argument(fmt::format("CANopen arm: {}: node id is not 1..127", joint_name(j)));
    if (!nodes.insert(j.node).second)
      throw std::invalid_argument(
          fmt::format("CANopen arm: {}: node {} drives another joint too", joint_name(j), j.node));
    if (!std::isfinite(j.lower) || !std::isfinite(j.upper) || j.lower > j.upper)
      throw std::invalid_argument(
          fmt::format("CANopen arm: {}: limits [{}, {}] are not an interval", joint_name(j), j.lower, j.upper));
    if (!std::isfinite(j.counts_per_unit) || j.counts_per_unit == 0)
      throw std::invalid_argument(fmt::format("CANopen arm: {}: counts per unit {} must be finite and not 0",
                                              joint_name(j), j.counts_per_unit));
    if (!(j.max_velocity > 0) || !std::isfinite(j.max_velocity))
      throw std::invalid_argument(
          fmt::format("CANopen arm: {}: maximum velocity {} must be more than 0", joint_name(j), j.max_velocity));
    if (!(j.max_acceleration >= 0) || !std::isfinite(j.max_acceleration))
      throw std::invalid_argument(
          fmt::format("CANopen arm: {}: maximum acceleration {} must be 0 (the default) or more", joint_name(j),
                      j.max_acceleration));
    drives_.emplace_back(master_, j.node);
  }
}

std::int32_t CanopenArm::to_counts(std::size_t i, double value) const {
  const double counts = std::round(value * joints_[i].counts_per_unit) + joints_[i].zero;
  if (counts < std::numeric_limits<std::int32_t>::min() || counts > std::numeric_limits<std::int32_t>::max())
    throw LimitError(fmt::format(
        "{}: position {} is {} drive counts, beyond what a drive's 32-bit position holds; no command was sent",
        joint_name(joints_[i]), value, counts));
  return static_cast<std::int32_t>(counts);
}

std::vector<std::string> CanopenArm::quick_stop_all() {
  std::vector<SdoWrite> writes;
  for (const ArmJoint& j : joints_)
    writes.push_back({j.node, cia402::od::kControlword, 0,
                      {static_cast<std::uint8_t>(cia402::cw::kQuickStop), cia402::cw::kQuickStop >> 8}});
  const std::vector<std::string> errors = master_.download_all(writes);
  std::vector<std::string> failures;
  for (std::size_t i = 0; i < joints_.size(); ++i)
    if (!errors[i].empty()) failures.push_back(fmt::format("{}: {}", joint_name(joints_[i]), errors[i]));
  return failures;
}

// Runs `f`; on a fault, quick-stops every joint and throws ArmStopped with the reason and the
// outcome of the stop. LimitError and argument errors pass through: nothing moved because of them.
template <class F>
auto CanopenArm::guarded(F&& f) -> decltype(f()) {
  std::string reason;
  int node = 0;
  try {
    return f();
  } catch (const LimitError&) {
    throw;
  } catch (const std::invalid_argument&) {
    throw;
  } catch (const ArmStopped&) {
    throw;
  } catch (const Interrupted& e) {  // not a fault: whoever interrupted stops the arm
    throw ArmStopped(0, fmt::format("arm stopped: {}", e.what()));
  } catch (const NodeFault& e) {
    reason = e.what();
    node = e.fault.node;
  } catch (const SdoAbort& e) {
    reason = e.what();
    node = e.node;
  } catch (const SdoTimeout& e) {
    reason = e.what();
    node = e.node;
  } catch (const JointFailure& e) {
    reason = e.what();
    node = e.node;
  } catch (const std::exception& e) {  // a timeout, a drive fault, the line gone
    reason = e.what();
  }
  if (node != 0 && reason.find("joint '") == std::string::npos)  // name the joint beside its node
    for (const ArmJoint& j : joints_)
      if (j.node == node) reason = fmt::format("joint '{}': {}", j.name, reason);
  const auto failures = quick_stop_all();
  std::string outcome = failures.empty() ? "every joint was sent quick stop"
                                         : fmt::format("quick stop failed on {} of {} joints: {}", failures.size(),
                                                       joints_.size(), failures.front());
  throw ArmStopped(node, fmt::format("arm stopped: {}; {}", reason, outcome));
}

void CanopenArm::start() {
  guarded([&] { start_up(); });
}

void CanopenArm::start_up() {
  auto notice = [&](const std::string& text) {
    if (options_.notice) options_.notice(text);
  };
  // Communication reset, then every node's boot-up: the nodes are on the bus, with these ids, and
  // their communication objects (PDOs, heartbeat) are at their defaults before they are configured.
  // What is already waiting on the line (a boot-up from before) is taken in first, so that it is
  // not taken for the answer.
  master_.spin_for(std::chrono::milliseconds(10));
  for (const ArmJoint& j : joints_) master_.nmt(NmtCommand::reset_communication, j.node);
  master_.spin_until(
      [&] {
        return std::none_of(joints_.begin(), joints_.end(), [&](const ArmJoint& j) { return master_.awaiting_boot(j.node); });
      },
      options_.enable_timeout);
  std::vector<std::string> silent;
  int first_silent = 0;
  for (const ArmJoint& j : joints_)
    if (master_.awaiting_boot(j.node)) {
      silent.push_back(joint_name(j));
      if (!first_silent) first_silent = j.node;
    }
  if (!silent.empty())
    throw JointFailure(first_silent,
                       fmt::format("no boot-up message within {} ms of an NMT reset communication from {} (is it on the "
                                   "bus, powered, with this node id?)",
                                   options_.enable_timeout.count(), fmt::join(silent, ", ")));
  // Only CiA 402 drives: 0x1000's low 16 bits name the device profile.
  for (const ArmJoint& j : joints_) {
    const auto type = master_.read<std::uint32_t>(j.node, 0x1000, 0);
    if ((type & 0xFFFF) != cia402::kDeviceProfile)
      throw JointFailure(j.node, fmt::format("{}: device type 0x{:08X} (0x1000) is device profile {}, not a CiA 402 drive "
                                             "(402): refused",
                                             joint_name(j), type, type & 0xFFFF));
  }
  // A drive in fault is the drive's news: its error code is told, and it is reset only with leave.
  for (std::size_t i = 0; i < joints_.size(); ++i) {
    const std::uint16_t word = drives_[i].statusword();
    if (cia402::decode(word) != cia402::State::fault) continue;
    const std::uint16_t code = drives_[i].error_code();
    const std::string what = fmt::format("{}: the drive is in fault at start-up, error code 0x{:04X} ({}), statusword 0x{:04X}",
                                         joint_name(joints_[i]), code, emcy_name(code), word);
    if (!options_.reset_faults)
      throw JointFailure(joints_[i].node, what + "; it is not reset unless allowed (reset_faults_at_start)");
    notice(what + "; resetting it, as allowed (reset_faults_at_start)");
    drives_[i].fault_reset(options_.enable_timeout);
  }
  for (std::size_t i = 0; i < joints_.size(); ++i) {
    const ArmJoint& j = joints_[i];
    master_.write<std::uint16_t>(j.node, 0x1017, 0, options_.heartbeat_ms);
    // The drive's own software limits, in counts, as a second line behind the check in move_to.
    const std::int32_t a = to_counts(i, j.lower), b = to_counts(i, j.upper);
    master_.write<std::int32_t>(j.node, cia402::od::kSoftwarePositionLimit, 1, std::min(a, b));
    master_.write<std::int32_t>(j.node, cia402::od::kSoftwarePositionLimit, 2, std::max(a, b));
    // The state a task watches, on every SYNC: one SYNC, one fresh sample of every drive.
    master_.configure_tpdo(j.node, 1,
                           PdoConfig{{{cia402::od::kStatusword, 0, 16}, {cia402::od::kPositionActual, 0, 32}}, 1});
    master_.configure_tpdo(j.node, 2, PdoConfig{{{cia402::od::kVelocityActual, 0, 32}}, 1});
    // Set-points by RPDO taking effect on the next SYNC: every joint starts its move at once.
    master_.configure_rpdo(j.node, 1,
                           PdoConfig{{{cia402::od::kControlword, 0, 16}, {cia402::od::kTargetPosition, 0, 32}}, 1});
    // The mode of operation before "operation enabled", as CiA 402 asks; the target where the
    // drive stands, so that nothing moves when it is enabled.
    master_.write<std::int32_t>(j.node, cia402::od::kTargetPosition, 0, drives_[i].position());
    drives_[i].set_mode(cia402::kProfilePosition);
    master_.nmt(NmtCommand::start, j.node);
    if (options_.heartbeat_ms > 0) master_.watch_heartbeat(j.node, options_.heartbeat_timeout);
  }
  for (std::size_t i = 0; i < joints_.size(); ++i) {
    drives_[i].enable(options_.enable_timeout);  // a fault now is new: not reset
    const auto v =
        static_cast<std::uint32_t>(std::max(1.0, std::abs(joints_[i].max_velocity * joints_[i].counts_per_unit)));
    drives_[i].set_profile(
        v, static_cast<std::uint32_t>(std::max(1.0, std::abs(acceleration(i) * joints_[i].counts_per_unit))));
  }
}

std::vector<std::int32_t> CanopenArm::checked_counts(const std::vector<double>& targets) const {
  if (targets.size() != joints_.size())
    throw LimitError(
        fmt::format("CANopen arm: {} targets for {} joints; no command was sent", targets.size(), joints_.size()));
  std::vector<std::int32_t> counts(targets.size());
  for (std::size_t i = 0; i < targets.size(); ++i) {
    const ArmJoint& j = joints_[i];
    if (!std::isfinite(targets[i]) || targets[i] < j.lower || targets[i] > j.upper)
      throw LimitError(fmt::format("{}: target {} is outside its limits [{}, {}]; no command was sent", joint_name(j),
                                   targets[i], j.lower, j.upper));
    counts[i] = to_counts(i, targets[i]);
  }
  return counts;
}

double CanopenArm::move_to(const std::vector<double>& targets, double speed) {
  if (targets.size() == joints_.size() && !(speed > 0 && speed <= 1))
    throw LimitError(
        fmt::format("CANopen arm: speed {} is not in (0, 1] of the maximum velocities; no command was sent", speed));
  const std::vector<std::int32_t> counts = checked_counts(targets);
  return guarded([&] {
    const auto now = read_positions();
    // One path s from 0 to 1 for every joint (joint i moves distance_i * s): the path's velocity and
    // acceleration are the largest every joint can follow, so the trapezoids are the same shape
    // and the joints start, cruise and arrive together.
    double path_velocity = std::numeric_limits<double>::infinity(), path_acceleration = path_velocity;
    for (std::size_t i = 0; i < joints_.size(); ++i) {
      const double distance = std::abs(targets[i] - now[i]);
      if (distance == 0) continue;
      path_velocity = std::min(path_velocity, joints_[i].max_velocity * speed / distance);
      path_acceleration = std::min(path_acceleration, acceleration(i) / distance);
    }
    double duration = 0;
    if (std::isfinite(path_velocity))
      duration = path_velocity * path_velocity >= path_acceleration  // no time to reach full speed
                     ? 2 * std::sqrt(1 / path_acceleration)
                     : 1 / path_velocity + path_velocity / path_acceleration;
    else
      path_velocity = path_acceleration = 0;
    for (std::size_t i = 0; i < joints_.size(); ++i) {
      const double distance =
          std::abs(static_cast<double>(counts[i]) - std::round(now[i] * joints_[i].counts_per_unit + joints_[i].zero));
      const auto at_least_one = [](double v) { return static_cast<std::uint32_t>(std::max(1.0, std::ceil(v))); };
      master_.write<std::uint32_t>(joints_[i].node, cia402::od::kProfileVelocity, 0,
                                   at_least_one(distance * path_velocity));
      master_.write<std::uint32_t>(joints_[i].node, cia402::od::kProfileAcceleration, 0,
                                   at_least_one(distance * path_acceleration));
      master_.write<std::uint32_t>(joints_[i].node, cia402::od::kProfileDeceleration, 0,
                                   at_least_one(distance * path_acceleration));
    }
    // The CiA 402 set-point handshake for all joints at once: bit 4 (new set-point) up with the
    // target on one SYNC, every drive acknowledges (statusword bit 12), bit 4 down on the next SYNC.
    const std::uint16_t base = cia402::cw::kEnableOperation | cia402::cw::kChangeImmediately;
    auto set_point = [&](std::uint16_t controlword) {
      for (std::size_t i = 0; i < joints_.size(); ++i) {
        const auto t = static_cast<std::uint32_t>(counts[i]);
        const std::array<std::uint8_t, 6> data{
            static_cast<std::uint8_t>(controlword), static_cast<std::uint8_t>(controlword >> 8),
            static_cast<std::uint8_t>(t),           static_cast<std::uint8_t>(t >> 8),
            static_cast<std::uint8_t>(t >> 16),     static_cast<std::uint8_t>(t >> 24)};
        master_.send_rpdo(joints_[i].node, 1, data);
      }
      sync(master_.options().sdo_timeout);  // its TPDO answers taken in here, so no later sample takes them for its own
    };
    set_point(base | cia402::cw::kNewSetPoint);
    // The acknowledges (statusword bit 12) come in the drives' PDOs answering a SYNC: the one that
    // carried the set-points, else one repeated every SYNC period. A drive that has not acknowledged
    // within one SDO timeout of the set-points' SYNC stops the arm (guarded: every joint is
    // quick-stopped), so the others do not move on alone for longer than that.
    const auto deadline = Clock::now() + master_.options().sdo_timeout;
    for (;;) {
      std::size_t missing = joints_.size();
      std::uint16_t word = 0;
      for (std::size_t i = 0; i < joints_.size() && missing == joints_.size(); ++i) {
        const can::Frame f = master_.tpdo(joints_[i].node, 1)->frame;
        const auto s = static_cast<std::uint16_t>(f.data[0] | f.data[1] << 8);
        check_drive(i, s);
        if (!(s & cia402::sw::kSetPointAcknowledge)) missing = i, word = s;
      }
      if (missing == joints_.size()) break;
      if (Clock::now() >= deadline)
        throw JointFailure(joints_[missing].node,
                           fmt::format("{}: did not acknowledge its set-point within {} ms of the SYNC that carried it "
                                       "(statusword 0x{:04X}, bit 12 clear)",
                                       joint_name(joints_[missing]), master_.options().sdo_timeout.count(), word));
      // The next SYNC a period on, or at the deadline: a missing acknowledge is found then, not a
      // period after it.
      master_.spin_for(std::clamp(std::chrono::ceil<std::chrono::milliseconds>(deadline - Clock::now()),
                                  std::chrono::milliseconds(1), options_.sync_period));
      sync(master_.options().sdo_timeout);
    }
    set_point(base);
    return duration;
  });
}

double CanopenArm::acceleration(std::size_t joint) const {
  const ArmJoint& j = joints_[joint];
  return j.max_acceleration > 0 ? j.max_acceleration : 10 * j.max_velocity;
}

void CanopenArm::check_drive(std::size_t i, std::uint16_t s) {
  master_.throw_if_faulted(joints_[i].node);
  const cia402::State state = cia402::decode(s);
  if (state == cia402::State::operation_enabled) return;
  const std::uint16_t code = state == cia402::State::fault ? drives_[i].error_code() : 0;
  throw JointFailure(joints_[i].node,
                     fmt::format("{}: the drive is in \"{}\" (statusword 0x{:04X}{})", joint_name(joints_[i]),
                                 cia402::to_string(state), s,
                                 code ? fmt::format(", error code 0x{:04X}: {}", code, emcy_name(code)) : ""));
}

bool CanopenArm::reached() {
  return guarded([&] {
    bool all = true;
    for (std::size_t i = 0; i < joints_.size(); ++i) {
      master_.throw_if_faulted(joints_[i].node);
      const std::uint16_t s = drives_[i].statusword();
      check_drive(i, s);
      all = all && (s & cia402::sw::kTargetReached);
    }
    return all;
  });
}

void CanopenArm::sync(std::chrono::milliseconds timeout) {
  const std::size_t n = joints_.size();
  auto count = [&](std::size_t i, int pdo) {
    const auto s = master_.tpdo(joints_[i].node, pdo);
    return s ? s->count : 0;
  };
  std::vector<std::uint64_t> before(2 * n);
  for (std::size_t i = 0; i < n; ++i) before[2 * i] = count(i, 1), before[2 * i + 1] = count(i, 2);
  auto answered = [&](std::size_t i) { return count(i, 1) > before[2 * i] && count(i, 2) > before[2 * i + 1]; };
  master_.send_sync();
  // Done when every drive answered, or as soon as one faulted (that fault is the news).
  master_.spin_until(
      [&] {
        if (!master_.faults().empty()) return true;
        for (std::size_t i = 0; i < n; ++i)
          if (!answered(i)) return false;
        return true;
      },
      timeout);
  for (const ArmJoint& j : joints_) master_.throw_if_faulted(j.node);  // the fault first: it is why others wait
  for (std::size_t i = 0; i < n; ++i)
    if (!answered(i))
      throw JointFailure(joints_[i].node, fmt::format("{}: its PDOs did not answer the SYNC within {} ms",
                                                      joint_name(joints_[i]), timeout.count()));
}

ArmSample CanopenArm::sample(std::chrono::milliseconds timeout) {
  return guarded([&] {
    sync(timeout);
    return read_sample(false);
  });
}

ArmSample CanopenArm::read_sample(bool cyclic) {
  {
    ArmSample out;
    out.reached = true;
    for (std::size_t i = 0; i < joints_.size(); ++i) {
      const ArmJoint& j = joints_[i];
      const can::Frame state = master_.tpdo(j.node, 1)->frame, velocity = master_.tpdo(j.node, 2)->frame;
      if (state.dlc != 6 || velocity.dlc != 4)
        throw JointFailure(j.node, fmt::format("{}: its PDOs have {} and {} bytes, expected 6 (statusword, position) "
                                               "and 4 (velocity)",
                                               joint_name(j), state.dlc, velocity.dlc));
      const auto word = static_cast<std::uint16_t>(state.data[0] | state.data[1] << 8);
      check_drive(i, word);
      if (cyclic && !(word & cia402::sw::kFollowsCommand))
        throw JointFailure(j.node, fmt::format("{}: does not follow its set-point (statusword 0x{:04X}, bit 12 clear "
                                               "on the SYNC that carried it)",
                                               joint_name(j), word));
      const auto le32 = [](const std::uint8_t* b) {
        return static_cast<std::int32_t>(static_cast<std::uint32_t>(b[0]) | static_cast<std::uint32_t>(b[1]) << 8 |
                                         static_cast<std::uint32_t>(b[2]) << 16 |
                                         static_cast<std::uint32_t>(b[3]) << 24);
      };
      out.positions.push_back((static_cast<double>(le32(&state.data[2])) - j.zero) / j.counts_per_unit);
      out.velocities.push_back(static_cast<double>(le32(&velocity.data[0])) / j.counts_per_unit);
      out.reached = out.reached && (word & cia402::sw::kTargetReached);
    }
    return out;
  }
}

void CanopenArm::begin_cyclic() {
  guarded([&] {
    const auto period = static_cast<std::uint8_t>(std::clamp<std::int64_t>(options_.sync_period.count(), 1, 255));
    for (std::size_t i = 0; i < joints_.size(); ++i) {
      const int node = joints_[i].node;
      master_.write<std::uint8_t>(node, cia402::od::kInterpolationPeriod, 1, period);
      master_.write<std::int8_t>(node, cia402::od::kInterpolationPeriod, 2, -3);  // milliseconds
      // Held where it stands: the first set-point it takes in the mode is its own position.
      master_.write<std::int32_t>(node, cia402::od::kTargetPosition, 0, drives_[i].position());
      drives_[i].set_mode(cia402::kCyclicSynchronousPosition);
      check_drive(i, drives_[i].statusword());
    }
  });
}

ArmSample CanopenArm::cycle(const std::vector<double>& set_points, std::chrono::milliseconds timeout) {
  const std::vector<std::int32_t> counts = checked_counts(set_points);
  return guarded([&] {
    for (std::size_t i = 0; i < joints_.size(); ++i) {
      const auto t = static_cast<std::uint32_t>(counts[i]);
      const std::uint16_t controlword = cia402::cw::kEnableOperation;
      const std::array<std::uint8_t, 6> data{
          static_cast<std::uint8_t>(controlword), static_cast<std::uint8_t>(controlword >> 8),
          static_cast<std::uint8_t>(t),           static_cast<std::uint8_t>(t >> 8),
          static_cast<std::uint8_t>(t >> 16),     static_cast<std::uint8_t>(t >> 24)};
      master_.send_rpdo(joints_[i].node, 1, data);
    }
    sync(timeout);
    return read_sample(true);
  });
}

void CanopenArm::end_cyclic() {
  guarded([&] {
    for (std::size_t i = 0; i < joints_.size(); ++i) {
      master_.write<std::int32_t>(joints_[i].node, cia402::od::kTargetPosition, 0, drives_[i].position());
      drives_[i].set_mode(cia402::kProfilePosition);
    }
  });
}

void CanopenArm::move_and_wait(const std::vector<double>& targets, double speed, std::chrono::milliseconds timeout) {
  const auto deadline = Clock::now() + timeout;
  move_to(targets, speed);
  while (!reached()) {
    if (Clock::now() >= deadline)
      guarded([&]() -> int { throw Error(fmt::format("the move did not end within {} ms", timeout.count())); });
    wait(std::chrono::milliseconds(5));
  }
}

void CanopenArm::wait(std::chrono::milliseconds duration) {
  guarded([&] { master_.spin_for(duration); });
}

std::vector<double> CanopenArm::read_positions() {
  std::vector<double> out(joints_.size());
  for (std::size_t i = 0; i < joints_.size(); ++i)
    out[i] = (static_cast<double>(drives_[i].position()) - joints_[i].zero) / joints_[i].counts_per_unit;
  return out;
}

std::vector<double> CanopenArm::positions() {
  return guarded([&] { return read_positions(); });
}

}  // namespace fba::canopen
