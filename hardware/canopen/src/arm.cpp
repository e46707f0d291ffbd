#include "fba/canopen/arm.hpp"

#include <algorithm>
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
  std::vector<std::string> failures;
  for (std::size_t i = 0; i < drives_.size(); ++i) {
    try {
      drives_[i].quick_stop();
    } catch (const std::exception& e) {
      failures.push_back(fmt::format("{}: {}", joint_name(joints_[i]), e.what()));
    }
  }
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
      master_.nmt(NmtCommand::start, j.node);
      if (options_.heartbeat_ms > 0) master_.watch_heartbeat(j.node, options_.heartbeat_timeout);
    }
    for (std::size_t i = 0; i < joints_.size(); ++i) {
      drives_[i].enable(options_.enable_timeout);
      const auto v =
          static_cast<std::uint32_t>(std::max(1.0, std::abs(joints_[i].max_velocity * joints_[i].counts_per_unit)));
      drives_[i].set_profile(v, 10 * v);
    }
  });
}

void CanopenArm::move_to(const std::vector<double>& targets, double speed) {
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
  guarded([&] {
    const auto now = read_positions();
    // The move takes as long as its slowest joint at full (scaled) speed; the others go slower.
    double duration = 0;
    for (std::size_t i = 0; i < joints_.size(); ++i)
      duration = std::max(duration, std::abs(targets[i] - now[i]) / (joints_[i].max_velocity * speed));
    for (std::size_t i = 0; i < joints_.size(); ++i) {
      const double distance =
          std::abs(static_cast<double>(counts[i]) - std::round(now[i] * joints_[i].counts_per_unit + joints_[i].zero));
      const double v = duration > 0 ? distance / duration : 1.0;
      master_.write<std::uint32_t>(joints_[i].node, cia402::od::kProfileVelocity, 0,
                                   static_cast<std::uint32_t>(std::max(1.0, std::ceil(v))));
    }
    for (std::size_t i = 0; i < joints_.size(); ++i) drives_[i].start_move(counts[i], options_.enable_timeout);
  });
}

bool CanopenArm::reached() {
  return guarded([&] {
    bool all = true;
    for (std::size_t i = 0; i < joints_.size(); ++i) {
      master_.throw_if_faulted(joints_[i].node);
      const std::uint16_t s = drives_[i].statusword();
      const cia402::State state = cia402::decode(s);
      if (state != cia402::State::operation_enabled) {
        const std::uint16_t code = state == cia402::State::fault ? drives_[i].error_code() : 0;
        throw JointFailure(joints_[i].node,
                           fmt::format("{}: the drive is in \"{}\" (statusword 0x{:04X}{})", joint_name(joints_[i]),
                                       cia402::to_string(state), s,
                                       code ? fmt::format(", error code 0x{:04X}: {}", code, emcy_name(code)) : ""));
      }
      all = all && (s & cia402::sw::kTargetReached);
    }
    return all;
  });
}

void CanopenArm::move_and_wait(const std::vector<double>& targets, double speed, std::chrono::milliseconds timeout) {
  const auto deadline = Clock::now() + timeout;
  move_to(targets, speed);
  while (!reached()) {
    if (Clock::now() >= deadline)
      guarded([&]() -> int { throw Error(fmt::format("the move did not end within {} ms", timeout.count())); });
    master_.spin_for(std::chrono::milliseconds(5));
  }
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
