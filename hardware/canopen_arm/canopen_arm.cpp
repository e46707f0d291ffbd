// hw.canopen_arm: the task's real arm, one CiA 402 drive per joint on a CANopen bus (SLCAN adapter
// or SocketCAN), the twin of sim.arm with the same ports and events (arm_ports.hpp) and the same
// URDF for kinematics and limits. It enables the drives, turns camera poses into joint targets by
// IK, checks every target against the URDF's limits before anything is sent, makes synchronised
// profile position moves, and publishes joint states from the drives' PDOs while they move.
// Any fault (a drive's EMCY or fault state, a silent drive, the line gone, persistent noise)
// quick-stops every joint and ends process() with an error naming the bus, the joint, its node and
// the reason, so the task's on_error policy applies. The safe state (a quick stop of every drive,
// its own bus messages) runs beside a process() still under way: the master takes one step of
// either at a time, and once the safe state has begun the master sends nothing else.
#include <atomic>
#include <chrono>
#include <cmath>
#include <deque>
#include <memory>
#include <optional>
#include <variant>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <fba/can/open_bus.hpp>
#include <fba/can/slcan.hpp>
#include <fba/canopen/arm.hpp>
#include <fba/component.hpp>

#include "arm_component.hpp"

namespace {

using Clock = std::chrono::steady_clock;
namespace canopen = fba::canopen;

std::string check_bus(const fba::ParamValues& p);
std::string check_rate(const fba::ParamValues& p);

class CanopenArmComponent final : public fba::arm::ArmComponent {
 public:
  static constexpr fba::Param<std::string> kDevice{
      "device", fba::required,
      "the CAN bus: slcan:/dev/ttyUSB0 (an SLCAN adapter on a serial line), can0 or socketcan:can0 (SocketCAN)"};
  static constexpr auto kBitrate =
      fba::Param<int>("bitrate", 500000,
                      "the CAN bitrate, bit/s, set on an SLCAN adapter (SocketCAN: set on the interface)")
          .range(10000, 1000000);
  static inline const auto kNodeIds =
      fba::Param<std::vector<double>>("node_ids", fba::required,
                                      "each joint's CANopen node id (1..127), in the arm's joint order")
          .range(1, 127);
  static inline const auto kCountsPerRad = fba::Param<std::vector<double>>(
      "counts_per_rad", fba::required,
      "each joint's encoder scale: drive position units per radian (per metre for a prismatic joint); negative "
      "when the drive counts the other way");
  static inline const auto kZeroCounts =
      fba::Param<std::vector<double>>("zero_counts", std::vector<double>{},
                                      "each joint's drive position at joint position 0; empty: 0 for every joint");
  static constexpr auto kRate =
      fba::Param<double>("rate", 50.0, "joint states per second while moving (the drives are sampled with a SYNC each)")
          .range(0.1, 1000.0);
  static constexpr auto kHeartbeatPeriod =
      fba::Param<int>("heartbeat_period_ms", 50, "the heartbeat period each drive is given (object 0x1017)")
          .range(1, 10000);
  static constexpr auto kHeartbeatTimeout =
      fba::Param<int>("heartbeat_timeout_ms", 300, "a drive not heard for this long is lost: the arm stops")
          .range(1, 60000);
  static constexpr auto kSdoTimeout =
      fba::Param<int>("sdo_timeout_ms", 200, "how long a drive may take to answer an SDO, or its PDOs a SYNC")
          .range(1, 10000);
  static constexpr auto kEnableTimeout =
      fba::Param<int>("enable_timeout_ms", 2000,
                      "how long a drive may take to reach \"operation enabled\" or take a set-point")
          .range(1, 60000);
  static constexpr auto kNoiseLimit =
      fba::Param<int>("noise_limit", 100,
                      "bad frames (line noise) tolerated within one second; more and the line is not trusted")
          .range(0, 1000000);

  static fba::Spec spec() {
    return fba::Spec::actuator(
               "hw.canopen_arm",
               "Real arm of CiA 402 drives on a CANopen bus (SLCAN or SocketCAN), one node per joint, "
               "kinematics and limits from a URDF (the twin of sim.arm): moves to camera poses or joint "
               "targets with synchronised profile position moves, quick-stops on any fault.")
        .add(kTarget, kJointTarget, kJointState, kCameraPose, kArrived, kUnreachable, kDevice, kBitrate, kNodeIds,
             kCountsPerRad, kZeroCounts, kUrdf, kBaseLink, kCameraLink, kSpeed, kAcceleration, kRate,
             kPositionTolerance, kOrientationTolerance, kAttempts, kPublishInitial, kHeartbeatPeriod, kHeartbeatTimeout,
             kSdoTimeout, kEnableTimeout, kNoiseLimit, kHeartbeatPeriod < kHeartbeatTimeout)
        .check(kDevice, check_bus)
        .check(kRate, check_rate)
        .blocking()
        .concurrent_safe_state();
  }

  explicit CanopenArmComponent(fba::Context& ctx)
      : ArmComponent(ctx),
        sdo_timeout_(ctx(kSdoTimeout)),
        noise_limit_(static_cast<std::uint64_t>(ctx(kNoiseLimit))) {
    const std::size_t n = model_.size();
    const std::vector<double> nodes = ctx(kNodeIds), counts = ctx(kCountsPerRad), zeros = ctx(kZeroCounts);
    auto per_joint = [&](const char* param, std::size_t size, bool may_be_empty) {
      if (size == n || (may_be_empty && size == 0)) return;
      throw std::runtime_error(fmt::format("parameter '{}' has {} values; the arm from '{}' to '{}' has {} joints ({})",
                                           param, size, model_.base_link(), model_.tip_link(), n, names()));
    };
    per_joint("node_ids", nodes.size(), false);
    per_joint("counts_per_rad", counts.size(), false);
    per_joint("zero_counts", zeros.size(), true);
    std::vector<canopen::ArmJoint> joints;
    for (std::size_t i = 0; i < n; ++i) {
      const auto& name = model_.joint_names()[i];
      const auto& limits = model_.limits()[i];
      if (nodes[i] != std::round(nodes[i]))
        throw std::runtime_error(
            fmt::format("parameter 'node_ids': {} (joint '{}') is not a whole number", nodes[i], name));
      if (zeros.size() == n && (zeros[i] != std::round(zeros[i]) || std::abs(zeros[i]) > 2147483647.0))
        throw std::runtime_error(fmt::format(
            "parameter 'zero_counts': {} (joint '{}') is not a whole 32-bit drive position", zeros[i], name));
      if (!std::isfinite(limits.lower) || !std::isfinite(limits.upper))
        throw std::runtime_error(
            fmt::format("joint '{}' of '{}' has no finite limits (a continuous joint): "
                        "hw.canopen_arm needs limits to check every command against",
                        name, ctx(kUrdf).string()));
      joints.push_back(canopen::ArmJoint{.name = name,
                                         .node = static_cast<int>(nodes[i]),
                                         .counts_per_unit = counts[i],
                                         .zero = zeros.empty() ? 0 : static_cast<std::int32_t>(zeros[i]),
                                         .lower = limits.lower,
                                         .upper = limits.upper,
                                         .max_velocity = limits.velocity * ctx(kSpeed),
                                         .max_acceleration = ctx(kAcceleration)});
    }
    // A wrong device is a configuration error, reported before the task runs.
    bus_ = fba::can::open_bus(ctx(kDevice), ctx(kBitrate), ctx.stop_token());
    master_ = std::make_unique<canopen::Master>(*bus_, canopen::MasterOptions{.sdo_timeout = sdo_timeout_});
    arm_ = std::make_unique<canopen::CanopenArm>(
        *master_, std::move(joints),
        canopen::ArmOptions{.heartbeat_ms = static_cast<std::uint16_t>(ctx(kHeartbeatPeriod)),
                            .heartbeat_timeout = std::chrono::milliseconds(ctx(kHeartbeatTimeout)),
                            .enable_timeout = std::chrono::milliseconds(ctx(kEnableTimeout))});
    ctx.set_trigger({fba::TriggerPolicy::Periodic, 1.0 / ctx(kRate)});
    ctx.log().info("{} joints from '{}' to '{}' ({}) on {}", n, model_.base_link(), model_.tip_link(), names(),
                   bus_->name());
  }

  void process() override {
    guarded([&] {
      if (auto in = ctx_(kTarget); in.has()) pending_.emplace_back(in.get());
      if (auto in = ctx_(kJointTarget); in.has()) pending_.emplace_back(in.get());
      step();
    });
  }

  // The targets' producers are done: the motion under way and those pending run to their end.
  void end_of_stream() override {
    guarded([&] {
      const auto period = std::chrono::milliseconds(std::max<std::int64_t>(1, std::llround(1000 / ctx_(kRate))));
      for (step(); moving_ || !pending_.empty(); step()) arm_->wait(period);
    });
  }

  // Quick stop of every drive at once, beside a process() that may still be running: from here on
  // the master sends nothing else, and that call's waits end. One SDO timeout bounds the wait for
  // all the confirmations; the drives that did not confirm are named.
  void safe_state() override {
    interrupted_ = true;
    master_->interrupt();
    if (!started_) return;  // the drives were never enabled by this run
    const auto failures = arm_->quick_stop_all();
    if (!failures.empty()) {
      const std::size_t confirmed = model_.size() - failures.size();
      throw std::runtime_error(fmt::format("{}: quick stop failed on {} of {} joints: {}{}", bus_->name(),
                                           failures.size(), model_.size(), fmt::join(failures, "; "),
                                           confirmed ? fmt::format("; the other {} confirmed it", confirmed) : ""));
    }
    ctx_.log().info("safe state: every joint quick-stopped");
  }

  // From the runtime's thread at shutdown: every wait on the bus ends within a few milliseconds.
  void interrupt() override {
    interrupted_ = true;
    master_->interrupt();
  }

 private:
  // Runs `f`; a fault (the arm already quick-stopped by CanopenArm) ends the call with an error
  // naming the bus. An interrupt is not a fault: the task is stopping, safe_state() follows.
  template <class F>
  void guarded(F&& f) {
    if (interrupted_) return;
    try {
      f();
    } catch (const std::exception& e) {
      if (interrupted_) return;
      throw std::runtime_error(fmt::format("hw.canopen_arm on {}: {}", bus_->name(), e.what()));
    }
  }

  // One tick: start the drives the first time, sample them, publish, end or start motions.
  void step() {
    const std::int64_t now = ctx_.now_ns();
    if (!started_) {
      started_ = true;  // from here on safe_state() quick-stops, even when start() fails half-way
      arm_->start();
    }
    check_noise();
    const canopen::ArmSample s = arm_->sample(sdo_timeout_);
    joints_ = Eigen::Map<const Eigen::VectorXd>(s.positions.data(), static_cast<Eigen::Index>(s.positions.size()));
    publish_initial(joints_, s.velocities, now);
    if (moving_) {
      publish_state(s.positions, s.velocities, now);
      if (s.reached) {
        moving_ = false;
        arrive(joints_, now);
      } else if (Clock::now() > deadline_) {
        const auto failures = arm_->quick_stop_all();
        throw std::runtime_error(fmt::format(
            "arm stopped: the move did not end within {:.1f} s (twice its planned {:.1f} s, and 1 s); {}",
            std::chrono::duration<double>(deadline_ - move_start_).count(), planned_s_,
            failures.empty() ? "every joint was sent quick stop" : "quick stop failed: " + failures.front()));
      }
    }
    while (!moving_ && !pending_.empty()) {
      const Request r = std::move(pending_.front());
      pending_.pop_front();
      start(r);
    }
  }

  // Plans a motion to a request from where the joints are, and starts it, or refuses it with
  // 'unreachable' (nothing is sent then).
  void start(const Request& r) {
    nlohmann::json target;
    Eigen::VectorXd goal;
    std::string why = goal_of(r, joints_, goal, target);
    if (why.empty()) {
      try {
        planned_s_ = arm_->move_to(fba::arm::values(goal));
        moving_ = true;
        move_start_ = Clock::now();
        deadline_ = move_start_ +
                    std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(2 * planned_s_ + 1.0));
        ctx_.log().debug("moving to {} in {:.3f} s", target.dump(), planned_s_);
        return;
      } catch (const canopen::LimitError& e) {  // beyond what the drive's counts hold: refused, nothing sent
        why = e.what();
      }
    }
    refuse(target, why);
  }

  // Line noise is skipped by the bus and counted; a burst is tolerated, a line that keeps
  // producing more than noise_limit bad frames a second is not.
  void check_noise() {
    const auto now = Clock::now();
    const std::uint64_t total = master_->discarded();
    noise_.push_back({now, total});
    while (noise_.size() > 1 && noise_[1].first <= now - std::chrono::seconds(1)) noise_.pop_front();
    const std::uint64_t recent = total - noise_.front().second;
    if (total > noise_reported_) {
      ctx_.log().warn("{}: {} bad frames skipped so far (the last: {})", bus_->name(), total,
                      master_->last_discard_reason());
      noise_reported_ = total;
    }
    if (recent <= noise_limit_) return;
    const auto failures = arm_->quick_stop_all();
    throw std::runtime_error(
        fmt::format("arm stopped: the line is too noisy to trust: {} bad frames within {:.1f} s (noise_limit {} a "
                    "second; the last: "
                    "{}); {}",
                    recent, std::chrono::duration<double>(now - noise_.front().first).count(), noise_limit_,
                    master_->last_discard_reason(),
                    failures.empty() ? "every joint was sent quick stop" : "quick stop failed: " + failures.front()));
  }

  const std::chrono::milliseconds sdo_timeout_;
  const std::uint64_t noise_limit_;
  std::unique_ptr<fba::can::CanBus> bus_;
  std::unique_ptr<canopen::Master> master_;
  std::unique_ptr<canopen::CanopenArm> arm_;
  // Set by interrupt() and safe_state(), from other threads than process()'s.
  std::atomic<bool> interrupted_{false};
  std::atomic<bool> started_{false};
  Eigen::VectorXd joints_;  // where the drives last said they are
  bool moving_ = false;
  double planned_s_ = 0;
  Clock::time_point move_start_, deadline_;
  // Targets that came during a motion, in order: each starts when the one before ends.
  std::deque<Request> pending_;
  std::deque<std::pair<Clock::time_point, std::uint64_t>> noise_;  // (when, bad frames so far), the last second
  std::uint64_t noise_reported_ = 0;
};

// The bus's form and the bitrate, checked where `fba-run --check` sees them (nothing is opened).
std::string check_bus(const fba::ParamValues& p) {
  const std::string device = p(CanopenArmComponent::kDevice);
  const bool slcan = device.rfind("slcan:", 0) == 0;
  const std::string interface = device.rfind("socketcan:", 0) == 0 ? device.substr(10) : device;
  if (slcan ? device.size() == 6 : interface.empty() || interface.find_first_of("/:") != std::string::npos)
    return "'" + device +
           "' is neither slcan:DEVICE (slcan:/dev/ttyUSB0) nor a SocketCAN interface (can0, socketcan:can0)";
  if (!slcan) return {};
  try {
    fba::can::slcan::bitrate_code(p(CanopenArmComponent::kBitrate));
  } catch (const std::invalid_argument& e) {
    return std::string("parameter 'bitrate': ") + e.what();
  }
  return {};
}

// The bus is read only while a tick runs: ticks further apart than the heartbeat timeout would
// leave the drives' heartbeats piling up unread in the line.
std::string check_rate(const fba::ParamValues& p) {
  const double period_ms = 1000 / p(CanopenArmComponent::kRate);
  const int timeout_ms = p(CanopenArmComponent::kHeartbeatTimeout);
  if (period_ms < timeout_ms) return {};
  return fmt::format("a tick every {:g} ms is not shorter than heartbeat_timeout_ms {}: raise the rate", period_ms,
                     timeout_ms);
}

}  // namespace

FBA_COMPONENT(CanopenArmComponent);
