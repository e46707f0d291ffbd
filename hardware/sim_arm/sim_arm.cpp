// sim.arm: the simulated twin of the task's arm (hw.canopen_arm is the real one, with the same
// ports and events). It takes a camera pose or joint target, plans a joint-space motion within
// the URDF's limits, and moves along it in the task's time: joint states at `rate` while it
// moves, and the camera's pose when it arrives, for sim.camera to render from.
#include <deque>
#include <dlfcn.h>

#include <cmath>
#include <optional>
#include <variant>

#include <nlohmann/json.hpp>

#include <fba/component.hpp>
#include <fba/types/joint_state.hpp>
#include <fba/types/pose.hpp>

#include "arm_model.hpp"
#include "arm_ports.hpp"

namespace {

using fba::arm::ArmModel;
using fba::arm::JointTrajectory;

// The project's arm, installed beside the plugins (FBA_ROBOTS_FROM_PLUGIN is relative to them).
std::filesystem::path default_urdf() {
  Dl_info info{};
  if (!dladdr(reinterpret_cast<void*>(&default_urdf), &info) || !info.dli_fname) return "wrist_camera_arm.urdf";
  return (std::filesystem::path(info.dli_fname).parent_path() / FBA_ROBOTS_FROM_PLUGIN / "wrist_camera_arm.urdf").lexically_normal();
}

nlohmann::json pose_json(const Eigen::Isometry3d& t) {
  const Eigen::Quaterniond q(t.linear());
  const Eigen::Vector3d p = t.translation();
  return {{"position", {p.x(), p.y(), p.z()}}, {"quaternion_wxyz", {q.w(), q.x(), q.y(), q.z()}}};
}

nlohmann::json joints_json(const Eigen::VectorXd& q) { return std::vector<double>(q.data(), q.data() + q.size()); }

class SimArm final : public fba::Component, public fba::arm::ArmPorts {
 public:
  static constexpr fba::Param<std::filesystem::path> kUrdf{
      "urdf", "", "the arm's URDF; empty: the project's wrist_camera_arm.urdf (a UR5-like 6R arm, camera on the wrist)"};
  static constexpr fba::Param<std::string> kBaseLink{"base_link", "world", "the frame target poses are given in"};
  static constexpr fba::Param<std::string> kCameraLink{"camera_link", "camera", "the camera's optical frame (z forward, x right, y down)"};
  static inline const auto kInitial = fba::Param<std::vector<double>>(
      "initial_joints", std::vector<double>{-0.4148, -2.1223, 2.2888, -2.2234, -1.3679, -0.3644},
      "joint positions at the start, in the arm's order (the default: the camera 0.35 m from the origin, 60 deg up on the arm's side, looking at it)");
  static constexpr auto kSpeed =
      fba::Param<double>("speed_scale", 0.5, "share of each joint's URDF velocity limit used by motions").range(0.01, 1.0);
  static constexpr auto kAcceleration =
      fba::Param<double>("acceleration", 3.0, "joint acceleration limit, rad/s^2 (m/s^2), every joint").range(0.01, 100.0);
  static constexpr auto kRate = fba::Param<double>("rate", 50.0, "joint states per second while moving (task time)").range(0.1, 1000.0);
  static constexpr auto kPositionTolerance =
      fba::Param<double>("position_tolerance", 1e-4, "how close IK must bring the camera to a target, m").range(1e-9, 0.1);
  static constexpr auto kOrientationTolerance =
      fba::Param<double>("orientation_tolerance", 1e-3, "how close IK must turn the camera to a target, rad").range(1e-9, 0.5);
  static constexpr auto kAttempts = fba::Param<int>("ik_attempts", 32, "IK starts: the current joints, then random seeds").range(1, 10000);
  static constexpr auto kPublishInitial =
      fba::Param<bool>("publish_initial", true, "publish the joint state and camera pose where the arm starts, at the first tick");

  static fba::Spec spec() {
    return fba::Spec::actuator("sim.arm",
                               "Simulated 6-joint arm with a wrist camera (URDF, Orocos KDL): moves to camera poses or joint targets "
                               "within the joint limits, in task time (the twin of hw.canopen_arm).")
        .add(kTarget, kJointTarget, kJointState, kCameraPose, kArrived, kUnreachable, kUrdf, kBaseLink, kCameraLink, kInitial, kSpeed,
             kAcceleration, kRate, kPositionTolerance, kOrientationTolerance, kAttempts, kPublishInitial);
  }

  explicit SimArm(fba::Context& ctx)
      : ctx_(ctx),
        model_(ctx(kUrdf).empty() ? default_urdf() : ctx(kUrdf), ctx(kBaseLink), ctx(kCameraLink)),
        publish_initial_(ctx(kPublishInitial)) {
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
    ik_.position_tolerance = ctx(kPositionTolerance);
    ik_.orientation_tolerance = ctx(kOrientationTolerance);
    ik_.attempts = ctx(kAttempts);
    ctx.set_trigger({fba::TriggerPolicy::Periodic, 1.0 / ctx(kRate)});
    ctx.log().info("{} joints from '{}' to '{}' ({})", n, model_.base_link(), model_.tip_link(), names());
  }

  void process() override {
    const std::int64_t now = ctx_.now_ns();
    publish_initial(now);
    if (auto in = ctx_(kTarget); in.has()) pending_.push_back(Pending{in.get(), now});
    if (auto in = ctx_(kJointTarget); in.has()) pending_.push_back(Pending{in.get(), now});
    advance(now);
  }

  // The targets' producers are done: the motions under way and pending run to their end in task
  // time (their samples stamped when they happen), since no tick comes after this.
  void end_of_stream() override {
    publish_initial(ctx_.now_ns());
    advance(std::numeric_limits<std::int64_t>::max());
  }

  // Stops where it is and drops what was pending.
  void safe_state() override {
    if (motion_) {
      Eigen::VectorXd velocity;
      motion_->sample(seconds_since_start(ctx_.now_ns()), joints_, velocity);
      ctx_.log().warn("safe state: stopped {:.3f} s into a motion of {:.3f} s", seconds_since_start(ctx_.now_ns()), motion_->duration());
    }
    motion_.reset();
    pending_.clear();
  }

 private:
  using Request = std::variant<fba::Pose, fba::JointState>;
  struct Pending {
    Request request;
    std::int64_t received_ns;
  };

  void publish_initial(std::int64_t now) {
    if (!publish_initial_) return;
    publish_initial_ = false;
    publish_state(joints_, Eigen::VectorXd::Zero(joints_.size()), now);
    ctx_(kCameraPose).emit(pose_at(joints_, now), now);
  }

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
      const std::int64_t end = start_ns_ + static_cast<std::int64_t>(std::ceil(motion_->duration() * 1e9));
      const bool to_the_end = until == std::numeric_limits<std::int64_t>::max();  // end of stream: every sample it would have had
      for (std::int64_t t = last_ns_ + period_ns(); t < std::min(until, end) && to_the_end; t += period_ns()) publish_along(t);
      if (until < end) {
        if (until > last_ns_) publish_along(until);
        return;
      }
      joints_ = motion_->goal();
      motion_.reset();
      stopped_ns_ = last_ns_ = end;
      publish_state(joints_, Eigen::VectorXd::Zero(joints_.size()), end);
      const fba::Pose pose = pose_at(joints_, end);
      ctx_(kCameraPose).emit(pose, end);
      ctx_.emit(kArrived, nlohmann::json{{"pose", pose_json(pose.world_from_frame)}, {"joints", joints_json(joints_)}}.dump());
    }
  }

  void publish_along(std::int64_t t) {
    Eigen::VectorXd q, v;
    motion_->sample(seconds_since_start(t), q, v);
    publish_state(q, v, t);
    last_ns_ = t;
  }

  // Plans the motion to a request from the current joints, or refuses it with 'unreachable'.
  void start(const Request& r, std::int64_t now) {
    nlohmann::json target;
    std::string why;
    Eigen::VectorXd goal;
    if (const auto* pose = std::get_if<fba::Pose>(&r)) {
      target = {{"pose", pose_json(pose->world_from_frame)}};
      const auto ik = model_.inverse(pose->world_from_frame, joints_, ik_);
      if (ik.ok) goal = ik.joints;
      else why = ik.why;
    } else {
      const auto& js = std::get<fba::JointState>(r);
      target = {{"names", js.names}, {"positions", js.positions}};
      why = joint_goal(js, goal);
    }
    if (!why.empty()) {
      ctx_.log().warn("unreachable target {}: {}", target.dump(), why);
      ctx_.emit(kUnreachable, nlohmann::json{{"target", target}, {"reason", why}}.dump());
      return;
    }
    motion_.emplace(joints_, goal, max_velocity_, max_acceleration_);
    start_ns_ = now;
    publish_along(now);
    ctx_.log().debug("moving to {} in {:.3f} s", target.dump(), motion_->duration());
  }

  // The joint vector a JointState asks for (by name, or in order), or why it cannot be had.
  std::string joint_goal(const fba::JointState& js, Eigen::VectorXd& goal) const {
    const auto& names = model_.joint_names();
    goal = joints_;
    if (js.names.empty()) {
      if (js.positions.size() != names.size())
        return std::to_string(js.positions.size()) + " positions without names; the arm has " + std::to_string(names.size()) +
               " joints (" + this->names() + ")";
      goal = Eigen::Map<const Eigen::VectorXd>(js.positions.data(), static_cast<Eigen::Index>(js.positions.size()));
    } else {
      if (js.names.size() != js.positions.size())
        return std::to_string(js.names.size()) + " names but " + std::to_string(js.positions.size()) + " positions";
      for (std::size_t i = 0; i < js.names.size(); ++i) {
        const auto it = std::find(names.begin(), names.end(), js.names[i]);
        if (it == names.end()) return "no joint '" + js.names[i] + "'; the arm's joints are " + this->names();
        goal(it - names.begin()) = js.positions[i];
      }
    }
    return model_.limit_violation(goal);
  }

  void publish_state(const Eigen::VectorXd& q, const Eigen::VectorXd& v, std::int64_t stamp_ns) {
    fba::JointState s;
    s.names = model_.joint_names();
    s.positions.assign(q.data(), q.data() + q.size());
    s.velocities.assign(v.data(), v.data() + v.size());
    s.stamp = static_cast<double>(stamp_ns) * 1e-9;
    ctx_(kJointState).emit(std::move(s), stamp_ns);
  }

  fba::Pose pose_at(const Eigen::VectorXd& q, std::int64_t stamp_ns) const {
    fba::Pose p;
    p.world_from_frame = model_.forward(q);
    p.stamp = static_cast<double>(stamp_ns) * 1e-9;
    return p;
  }

  double seconds_since_start(std::int64_t t) const { return static_cast<double>(t - start_ns_) * 1e-9; }
  std::int64_t period_ns() const { return std::max<std::int64_t>(1, std::llround(1e9 / ctx_(kRate))); }

  std::string names() const {
    std::string s;
    for (const auto& n : model_.joint_names()) s += (s.empty() ? "" : ", ") + n;
    return s;
  }

  fba::Context& ctx_;
  const ArmModel model_;
  Eigen::VectorXd joints_;  // where the arm is when not moving
  Eigen::VectorXd max_velocity_, max_acceleration_;
  fba::arm::IkOptions ik_;
  std::optional<JointTrajectory> motion_;
  std::int64_t start_ns_ = 0;    // of the motion
  std::int64_t last_ns_ = 0;     // the last time the motion was published
  std::int64_t stopped_ns_ = 0;  // when the last motion ended
  // Targets that came during a motion, in order: each starts when the one before ends (a planner
  // may ask for several views at once; none is dropped).
  std::deque<Pending> pending_;
  bool publish_initial_;
};

}  // namespace

FBA_COMPONENT(SimArm);
