// hw.canopen_arm: the task's real arm, one CiA 402 drive per joint on a CANopen bus (SLCAN adapter
// or SocketCAN), the twin of sim.arm with the same ports and events (arm_ports.hpp) and the same
// URDF for kinematics and limits. Its constructor starts the drives (communication reset and
// boot-up, device type, a drive found in fault, mode of operation, enable): a device that fails
// there is an fba::DeviceError naming it (exit 3), every joint quick-stopped. It turns camera poses
// into joint targets by IK, checks every target against the URDF's limits before anything is sent,
// makes synchronised profile position moves, follows trajectories in cyclic synchronous position
// (every drive takes its set-point on the same SYNC), and publishes joint states from the drives'
// PDOs while they move. Any fault (a drive's EMCY or fault state, a silent drive, a set-point not
// taken, the line gone, persistent noise) quick-stops every joint and ends process() with an error
// naming the bus, the joint, its node and the reason, so the task's on_error policy applies. The
// safe state (a quick stop of every drive, its own bus messages) runs beside a process() still under
// way: the master takes one step of either at a time, and once the safe state has begun the master
// sends nothing else.
//
// Why cyclic synchronous position (CiA 402 mode 8) for trajectories, and not profile position with
// set-points released by SYNC: a reach plan is already a timed path sampled every few tens of
// milliseconds, and in mode 8 each drive takes the path's position for the next SYNC on that SYNC,
// so every joint is where the plan says at the same instant by construction, and a drive that does
// not take its set-point shows it (statusword bit 12) on the very SYNC it missed, before any other
// joint is given the next one. Profile position would make each waypoint a move of its own, with
// its own trapezoid and the set-point handshake (bit 4 up, acknowledge, bit 4 down: two SYNCs a
// waypoint), stopping at every waypoint unless the vendor's blending of buffered set-points
// (change-on-set-point, end velocities) is used, which drives do differently. Mode 8 is also what
// the emulator can play faithfully: CiA 402 defines it completely (the set-point before a SYNC,
// taken on it, followed over the interpolation period 0x60C2), where profile position's blending is
// each vendor's own.
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
#include <stop_token>
#include <fba/can/slcan.hpp>
#include <fba/canopen/arm.hpp>
#include <fba/component.hpp>

#include "arm_component.hpp"
#include "launcher.hpp"

namespace {

using Clock = std::chrono::steady_clock;
namespace canopen = fba::canopen;

std::string check_bus(const fba::ParamValues& p);
std::string check_emulator(const fba::ParamValues& p);
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
  static constexpr fba::Param<bool> kResetFaults{
      "reset_faults_at_start", false,
      "reset a drive found in fault at start-up (its error code, 0x603F, is logged either way); false: refuse to "
      "start, naming the drive and its error code"};
  static constexpr fba::Param<std::string> kEmulator{
      "emulator", "",
      "an emulator program, with its options, started when the device does not exist or does not answer: it "
      "plays the arm on a pseudo-terminal linked at the device's path and is stopped at the end (the emulated "
      "profile: fba-canopen-arm-emulator); empty: never"};
  static constexpr auto kNoiseLimit =
      fba::Param<int>("noise_limit", 100,
                      "bad frames (line noise) tolerated within one second; more and the line is not trusted")
          .range(0, 1000000);

  static fba::Spec spec() {
    fba::Spec spec = fba::Spec::actuator(
        "hw.canopen_arm",
        "Real arm of CiA 402 drives on a CANopen bus (SLCAN or SocketCAN), one node per joint, "
        "kinematics and limits from a URDF (the twin of sim.arm): moves to camera poses or joint "
        "targets with synchronised profile position moves, quick-stops on any fault.");
    spec.add(kTarget, kJointTarget, kTrajectory, kJointState, kCameraPose, kRobot, kArrived, kUnreachable, kDevice, kBitrate, kNodeIds,
             kCountsPerRad, kZeroCounts);
    Robot::add(spec)
        .add(kBaseLink, kCameraLink, kSpeed, kAcceleration, kRate, kPositionTolerance, kOrientationTolerance, kAttempts,
             kInitialCameraPose, kCollisionCheck, kHeartbeatPeriod, kHeartbeatTimeout, kSdoTimeout, kEnableTimeout, kResetFaults,
             kEmulator, kNoiseLimit, kHeartbeatPeriod < kHeartbeatTimeout)
        .check(kDevice, check_bus)
        .check(kEmulator, check_emulator)
        .check(kRate, check_rate)
        .blocking()
        .concurrent_safe_state();
    return spec;
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
                        name, robot_.name));
      joints.push_back(canopen::ArmJoint{.name = name,
                                         .node = static_cast<int>(nodes[i]),
                                         .counts_per_unit = counts[i],
                                         .zero = zeros.empty() ? 0 : static_cast<std::int32_t>(zeros[i]),
                                         .lower = limits.lower,
                                         .upper = limits.upper,
                                         .max_velocity = limits.velocity * ctx(kSpeed),
                                         .max_acceleration = ctx(kAcceleration)});
    }
    // The device: a line that cannot be opened, or an adapter that does not answer, is the device's
    // failure (exit 3), not the task's.
    try {
      bus_ = open(ctx);
    } catch (const std::exception& e) {
      if (ctx.stop_token().stop_requested()) throw;
      throw fba::DeviceError(fmt::format("hw.canopen_arm on {}: {}", ctx(kDevice), e.what()));
    }
    master_ = std::make_unique<canopen::Master>(*bus_, canopen::MasterOptions{.sdo_timeout = sdo_timeout_});
    period_ = std::chrono::milliseconds(std::max<std::int64_t>(1, std::llround(1000 / ctx(kRate))));
    arm_ = std::make_unique<canopen::CanopenArm>(
        *master_, std::move(joints),
        canopen::ArmOptions{.heartbeat_ms = static_cast<std::uint16_t>(ctx(kHeartbeatPeriod)),
                            .heartbeat_timeout = std::chrono::milliseconds(ctx(kHeartbeatTimeout)),
                            .enable_timeout = std::chrono::milliseconds(ctx(kEnableTimeout)),
                            .reset_faults = ctx(kResetFaults),
                            .sync_period = period_,
                            .notice = [&ctx](const std::string& s) { ctx.log().warn("{}", s); }});
    ctx.set_trigger({fba::TriggerPolicy::Periodic, 1.0 / ctx(kRate)});
    ctx.log().info("{} joints from '{}' to '{}' ({}) on {}: starting the drives", n, model_.base_link(),
                   model_.tip_link(), names(), bus_->name());
    // Start-up, now, so that a device that fails is reported before the task runs. A stop of the
    // task meanwhile ends every wait on the bus at once; the drives are quick-stopped either way.
    std::stop_callback on_stop(ctx.stop_token(), [this] { master_->interrupt(); });
    try {
      started_ = true;  // from here on the drives may be enabled: safe_state() quick-stops
      arm_->start();
    } catch (const std::exception& e) {
      if (ctx.stop_token().stop_requested()) {
        arm_->quick_stop_all();  // not constructed, so no safe_state(): the stop is sent here
        throw;
      }
      throw fba::DeviceError(fmt::format("hw.canopen_arm on {}: {}", bus_->name(), e.what()));
    }
    ctx.log().info("{}: every drive enabled", bus_->name());
  }

  void process() override {
    guarded([&] {
      if (auto in = ctx_(kTarget); in.has()) pending_.emplace_back(in.get());
      if (auto in = ctx_(kJointTarget); in.has()) pending_.emplace_back(in.get());
      step();
      if (auto in = ctx_(kTrajectory); in.has()) begin_following(in.get());
    });
  }

  // The targets' producers are done: the motion under way and those pending run to their end (a
  // trajectory on the task's clock, which the executor keeps moving).
  void end_of_stream() override {
    guarded([&] {
      for (step(); moving_ || following_ || !pending_.empty(); step()) arm_->wait(period_);
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

  // The line to the drives. When it does not open (nothing there, or an adapter that does not answer)
  // and an emulator is configured, the emulator is started at the device's path (never in place of a
  // real device: only where nothing is, or a symbolic link), and the line opened to it.
  std::unique_ptr<fba::can::CanBus> open(fba::Context& ctx) {
    const std::string device = ctx(kDevice), emulator = ctx(kEmulator);
    try {
      return fba::can::open_bus(device, ctx(kBitrate), ctx.stop_token());
    } catch (const std::exception& e) {
      const std::string path = device.substr(6);  // after slcan: (check_emulator)
      if (emulator.empty() || ctx.stop_token().stop_requested() || !fba::emulators::free_for_emulator(path)) throw;
      ctx.log().info("{}: {}; starting the emulator: {}", device, e.what(), emulator);
      emulator_.emplace(emulator, path, ctx.stop_token());
      ctx.log().info("{}: played by {} (pid {})", device, emulator_->program(), emulator_->pid());
      return fba::can::open_bus(device, ctx(kBitrate), ctx.stop_token());
    }
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

  // One tick: sample the drives (or give them the trajectory's next set-points), publish, end or
  // start motions.
  void step() {
    const std::int64_t now = ctx_.now_ns();
    check_noise();
    if (following_) {
      follow(now);
      return;
    }
    const canopen::ArmSample s = arm_->sample(sdo_timeout_);
    joints_ = Eigen::Map<const Eigen::VectorXd>(s.positions.data(), static_cast<Eigen::Index>(s.positions.size()));
    publish_initial(joints_, s.velocities, now);
    if (moving_) {
      // At the target the drives stand still: the state says so, which is what reach planning
      // waits for before it plans from these joints.
      publish_state(s.positions, s.reached ? std::vector<double>(s.positions.size(), 0.0) : s.velocities, now);
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

  // A trajectory from where the arm stands, on the task's clock from now: the drives go to cyclic
  // synchronous position and take the first set-point at once. Refused with 'unreachable' (nothing
  // sent) when it does not fit the arm or comes while the arm moves.
  void begin_following(const fba::JointTrajectory& trajectory) {
    nlohmann::json target;
    fba::arm::TimedPath path;
    const bool busy = moving_ || following_ || !pending_.empty();
    std::string why = path_of(trajectory, joints_, path, target);
    if (busy) why = "the arm is moving: a trajectory starts where the arm stands still";
    if (!why.empty()) {
      refuse(target, why);
      return;
    }
    start_ns_ = ctx_.now_ns();
    path_ = std::move(path);
    arm_->begin_cyclic();
    following_ = true;
    settle_deadline_.reset();
    ctx_.log().info("following a trajectory of {} waypoints, {:.3f} s", path_.size(), path_.duration());
    follow(ctx_.now_ns());
  }

  // One SYNC of a trajectory: every drive is given the path's position for the next SYNC (where it
  // is to be one period from now), and reports where it is. The end: the last waypoint has been
  // every drive's set-point for two SYNCs and one period of time (the drives follow their
  // set-points a period behind) and every joint is within kSettleTolerance of it; then the drives
  // go back to profile position, where they stand, and the arm has arrived.
  void follow(std::int64_t now) {
    const double t = static_cast<double>(now - start_ns_) * 1e-9;
    const double ahead = t + std::chrono::duration<double>(period_).count();
    Eigen::VectorXd q, v;
    path_.sample(ahead, q, v);
    const canopen::ArmSample s = arm_->cycle(fba::arm::values(q), sdo_timeout_);
    joints_ = Eigen::Map<const Eigen::VectorXd>(s.positions.data(), static_cast<Eigen::Index>(s.positions.size()));
    publish_initial(joints_, s.velocities, now);
    publish_state(s.positions, s.velocities, now);
    if (ahead < path_.duration()) return;
    if (!settle_deadline_) {  // the first SYNC with the last waypoint
      settle_from_ = Clock::now();
      settle_deadline_ = settle_from_ + std::chrono::seconds(1);
      final_syncs_ = 0;
    }
    ++final_syncs_;
    if (final_syncs_ < 2 || Clock::now() - settle_from_ < period_ ||
        (joints_ - path_.goal()).cwiseAbs().maxCoeff() > kSettleTolerance) {
      if (Clock::now() < *settle_deadline_) return;
      const auto failures = arm_->quick_stop_all();
      throw std::runtime_error(fmt::format(
          "arm stopped: the joints did not settle within {} rad of the trajectory's end within 1 s of it (the "
          "farthest {:.4f} rad away); {}",
          kSettleTolerance, (joints_ - path_.goal()).cwiseAbs().maxCoeff(),
          failures.empty() ? "every joint was sent quick stop" : "quick stop failed: " + failures.front()));
    }
    following_ = false;
    arm_->end_cyclic();
    publish_state(fba::arm::values(joints_), std::vector<double>(static_cast<std::size_t>(joints_.size()), 0.0), now);  // settled: still
    arrive(joints_, now);
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

  // How close to a trajectory's last waypoint every joint must come for it to have arrived, rad.
  static constexpr double kSettleTolerance = 1e-3;

  const std::chrono::milliseconds sdo_timeout_;
  const std::uint64_t noise_limit_;
  // The emulator this driver started, if any: stopped after the line (declared first, gone last).
  std::optional<fba::emulators::LaunchedEmulator> emulator_;
  std::chrono::milliseconds period_{20};  // a tick: one SYNC
  std::unique_ptr<fba::can::CanBus> bus_;
  std::unique_ptr<canopen::Master> master_;
  std::unique_ptr<canopen::CanopenArm> arm_;
  // Set by interrupt() and safe_state(), from other threads than process()'s.
  std::atomic<bool> interrupted_{false};
  std::atomic<bool> started_{false};
  Eigen::VectorXd joints_;  // where the drives last said they are
  bool moving_ = false;
  bool following_ = false;        // a trajectory, in cyclic synchronous position
  fba::arm::TimedPath path_;      // the trajectory followed
  std::int64_t start_ns_ = 0;     // when it arrived, on the task's clock: its time 0
  std::optional<Clock::time_point> settle_deadline_;
  Clock::time_point settle_from_;
  int final_syncs_ = 0;
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

// An emulator plays an SLCAN adapter on a pseudo-terminal: the device must be slcan:PATH.
std::string check_emulator(const fba::ParamValues& p) {
  if (p(CanopenArmComponent::kEmulator).empty() || p(CanopenArmComponent::kDevice).rfind("slcan:", 0) == 0) return {};
  return "an emulator plays an SLCAN adapter on a pseudo-terminal: 'device' must be slcan:PATH, not '" +
         p(CanopenArmComponent::kDevice) + "'";
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
