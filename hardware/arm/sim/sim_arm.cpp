// sim.arm: the simulated twin of the task's arm (hw.canopen_arm is the real one, with the same
// ports and events). It takes a camera pose or joint target, plans a joint-space motion within
// the URDF's limits, and moves along it in the task's time: joint states at `rate` while it
// moves, and the camera's pose when it arrives, for sim.camera to render from. A timed trajectory
// (a reach plan) is followed kinematically on the task's clock from when it arrives.
#include <cmath>
#include <deque>
#include <limits>
#include <optional>
#include <variant>

#include <fba/component.hpp>

#include "arm_component.hpp"

namespace {

using fba::arm::JointTrajectory;
using fba::arm::TimedPath;
using fba::arm::values;

// What the arm follows: a planned motion to a target, or a trajectory it was given.
using Motion = std::variant<JointTrajectory, TimedPath>;
double duration(const Motion& m) {
  return std::visit([](const auto& x) { return x.duration(); }, m);
}
const Eigen::VectorXd& goal(const Motion& m) {
  return std::visit([](const auto& x) -> const Eigen::VectorXd& { return x.goal(); }, m);
}
void sample(const Motion& m, double t, Eigen::VectorXd& q, Eigen::VectorXd& v) {
  std::visit([&](const auto& x) { x.sample(t, q, v); }, m);
}

class SimArm final : public fba::arm::ArmComponent {
 public:
  static inline const auto kInitial = fba::Param<std::vector<double>>(
      "initial_joints", std::vector<double>{-0.4148, -2.1223, 2.2888, -2.2234, -1.3679, -0.3644},
      "joint positions at the start, in the arm's order (the default: the camera 0.35 m from the origin, 60 deg up on the arm's side, looking at it)");
  static constexpr auto kRate = fba::Param<double>("rate", 50.0, "joint states per second while moving (task time)").range(0.1, 1000.0);

  static fba::Spec spec() {
    fba::Spec spec = fba::Spec::actuator("sim.arm",
                                         "Simulated 6-joint arm with a wrist camera (URDF, Orocos KDL): moves to camera poses or joint "
                                         "targets within the joint limits, in task time (the twin of hw.canopen_arm).");
    spec.add(kTarget, kJointTarget, kTrajectory, kJointState, kCameraPose, kRobot, kArrived, kUnreachable);
    Robot::add(spec).add(kBaseLink, kCameraLink, kInitial, kSpeed, kAcceleration, kRate, kPositionTolerance, kOrientationTolerance,
                         kAttempts, kInitialCameraPose, kCollisionCheck);
    return spec;
  }

  explicit SimArm(fba::Context& ctx) : ArmComponent(ctx) {
    const auto n = static_cast<Eigen::Index>(model_.size());
    const std::vector<double> initial = ctx(kInitial);
    if (initial.size() != model_.size())
      throw std::runtime_error("parameter 'initial_joints' has " + std::to_string(initial.size()) + " positions; the arm from '" +
                               model_.base_link() + "' to '" + model_.tip_link() + "' has " + std::to_string(n) + " joints (" +
                               names() + ")");
    joints_ = Eigen::Map<const Eigen::VectorXd>(initial.data(), n);
    if (const auto bad = model_.limit_violation(joints_); !bad.empty()) throw std::runtime_error("parameter 'initial_joints': " + bad);
    max_velocity_.resize(n);
    for (Eigen::Index i = 0; i < n; ++i) max_velocity_(i) = model_.limits()[i].velocity * ctx(kSpeed);
    max_acceleration_ = Eigen::VectorXd::Constant(n, ctx(kAcceleration));
    ctx.set_trigger({fba::TriggerPolicy::Periodic, 1.0 / ctx(kRate)});
    ctx.log().info("{} joints from '{}' to '{}' ({})", n, model_.base_link(), model_.tip_link(), names());
  }

  void process() override {
    const std::int64_t now = ctx_.now_ns();
    publish_initial(joints_, still(), now);
    if (auto in = ctx_(kTarget); in.has()) pending_.push_back(Pending{in.get(), now});
    if (auto in = ctx_(kJointTarget); in.has()) pending_.push_back(Pending{in.get(), now});
    advance(now);
    if (auto in = ctx_(kTrajectory); in.has()) follow(in.get(), now);
  }

  // The targets' producers are done: the motions under way and pending run to their end in task
  // time (their samples stamped when they happen), since no tick comes after this.
  void end_of_stream() override {
    publish_initial(joints_, still(), ctx_.now_ns());
    advance(std::numeric_limits<std::int64_t>::max());
  }

  // Stops where it is and drops what was pending.
  void safe_state() override {
    if (motion_) {
      Eigen::VectorXd velocity;
      sample(*motion_, seconds_since_start(ctx_.now_ns()), joints_, velocity);
      ctx_.log().warn("safe state: stopped {:.3f} s into a motion of {:.3f} s", seconds_since_start(ctx_.now_ns()), duration(*motion_));
    }
    motion_.reset();
    pending_.clear();
  }

 private:
  struct Pending {
    Request request;
    std::int64_t received_ns;
  };

  // Moves the arm to time `until`: starts pending motions, publishes along them, ends them.
  void advance(std::int64_t until) {
    for (;;) {
      if (!motion_) {
        if (pending_.empty()) return;
        const Pending p = std::move(pending_.front());
        pending_.pop_front();
        start(p.request, std::max(p.received_ns, stopped_ns_));
        continue;
      }
      const std::int64_t end = start_ns_ + static_cast<std::int64_t>(std::ceil(duration(*motion_) * 1e9));
      const bool to_the_end = until == std::numeric_limits<std::int64_t>::max();  // end of stream: every sample it would have had
      for (std::int64_t t = last_ns_ + period_ns(); t < std::min(until, end) && to_the_end; t += period_ns()) publish_along(t);
      if (until < end) {
        if (until > last_ns_) publish_along(until);
        return;
      }
      joints_ = goal(*motion_);
      motion_.reset();
      stopped_ns_ = last_ns_ = end;
      publish_state(values(joints_), still(), end);
      arrive(joints_, end);
    }
  }

  void publish_along(std::int64_t t) {
    Eigen::VectorXd q, v;
    sample(*motion_, seconds_since_start(t), q, v);
    publish_state(values(q), values(v), t);
    last_ns_ = t;
  }

  // Plans the motion to a request from the current joints, or refuses it with 'unreachable'.
  void start(const Request& r, std::int64_t now) {
    nlohmann::json target;
    Eigen::VectorXd goal;
    if (const std::string why = goal_of(r, joints_, goal, target); !why.empty()) {
      refuse(target, why);
      return;
    }
    motion_.emplace(JointTrajectory(joints_, goal, max_velocity_, max_acceleration_));
    start_ns_ = now;
    publish_along(now);
    ctx_.log().debug("moving to {} in {:.3f} s", target.dump(), duration(*motion_));
  }

  // Follows a trajectory from now, on the task's clock, or refuses it with 'unreachable': one that
  // does not fit the arm, or that comes while the arm moves (a trajectory starts where it stands).
  void follow(const fba::JointTrajectory& trajectory, std::int64_t now) {
    nlohmann::json target;
    TimedPath path;
    std::string why = motion_ || !pending_.empty() ? "the arm is moving: a trajectory starts where the arm stands still"
                                                   : path_of(trajectory, joints_, path, target);
    if (!why.empty()) {
      if (target.is_null()) path_of(trajectory, joints_, path, target);  // the trajectory, for the event
      refuse(target, why);
      return;
    }
    ctx_.log().info("following a trajectory of {} waypoints, {:.3f} s", path.size(), path.duration());
    motion_.emplace(std::move(path));
    start_ns_ = now;
    publish_along(now);
  }

  std::vector<double> still() const { return std::vector<double>(joints_.size(), 0.0); }  // velocities at rest
  double seconds_since_start(std::int64_t t) const { return static_cast<double>(t - start_ns_) * 1e-9; }
  std::int64_t period_ns() const { return std::max<std::int64_t>(1, std::llround(1e9 / ctx_(kRate))); }

  Eigen::VectorXd joints_;  // where the arm is when not moving
  Eigen::VectorXd max_velocity_, max_acceleration_;
  std::optional<Motion> motion_;
  std::int64_t start_ns_ = 0;    // of the motion
  std::int64_t last_ns_ = 0;     // the last time the motion was published
  std::int64_t stopped_ns_ = 0;  // when the last motion ended
  // Targets that came during a motion, in order: each starts when the one before ends (a planner
  // may ask for several views at once; none is dropped).
  std::deque<Pending> pending_;
};

}  // namespace

FBA_COMPONENT(SimArm);
