#include "fba/canopen/arm.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <set>

#include <fmt/format.h>

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
  guarded([&] {
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
      master_.nmt(NmtCommand::start, j.node);
      if (options_.heartbeat_ms > 0) master_.watch_heartbeat(j.node, options_.heartbeat_timeout);
    }
    for (std::size_t i = 0; i < joints_.size(); ++i) {
      drives_[i].enable(options_.enable_timeout);
      const auto v =
          static_cast<std::uint32_t>(std::max(1.0, std::abs(joints_[i].max_velocity * joints_[i].counts_per_unit)));
      drives_[i].set_profile(
          v, static_cast<std::uint32_t>(std::max(1.0, std::abs(acceleration(i) * joints_[i].counts_per_unit))));
    }
  });
}

double CanopenArm::move_to(const std::vector<double>& targets, double speed) {
  if (targets.size() != joints_.size())
    throw LimitError(
        fmt::format("CANopen arm: {} targets for {} joints; no command was sent", targets.size(), joints_.size()));
  if (!(speed > 0 && speed <= 1))
    throw LimitError(
        fmt::format("CANopen arm: speed {} is not in (0, 1] of the maximum velocities; no command was sent", speed));
  std::vector<std::int32_t> counts(targets.size());
  for (std::size_t i = 0; i < targets.size(); ++i) {
    const ArmJoint& j = joints_[i];
    if (!std::isfinite(targets[i]) || targets[i] < j.lower || targets[i] > j.upper)
      throw LimitError(fmt::format("{}: target {} is outside its limits [{}, {}]; no command was sent", joint_name(j),
                                   targets[i], j.lower, j.upper));
    counts[i] = to_counts(i, targets[i]);
  }
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
      sync(options_.enable_timeout);  // its TPDO answers taken in here, so no later sample takes them for its own
    };
    set_point(base | cia402::cw::kNewSetPoint);
    const auto deadline = Clock::now() + options_.enable_timeout;
    for (std::size_t i = 0; i < joints_.size(); ++i) {
      for (std::uint16_t s = drives_[i].statusword(); !(s & cia402::sw::kSetPointAcknowledge);
           s = drives_[i].statusword()) {
        check_drive(i, s);
        if (Clock::now() > deadline)
          throw JointFailure(joints_[i].node,
                             fmt::format("{}: no set-point acknowledge within {} ms (statusword 0x{:04X})",
                                         joint_name(joints_[i]), options_.enable_timeout.count(), s));
        master_.spin_for(std::chrono::milliseconds(1));
      }
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
