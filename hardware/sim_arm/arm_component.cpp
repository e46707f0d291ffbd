#include "arm_component.hpp"

#include <dlfcn.h>

#include <algorithm>

namespace fba::arm {

namespace {

// The project's arm, installed beside the plugins (FBA_ROBOTS_FROM_PLUGIN is relative to them);
// linked into each arm plugin, dladdr names that plugin.
std::filesystem::path default_urdf() {
  Dl_info info{};
  if (!dladdr(reinterpret_cast<void*>(&default_urdf), &info) || !info.dli_fname) return "wrist_camera_arm.urdf";
  return (std::filesystem::path(info.dli_fname).parent_path() / FBA_ROBOTS_FROM_PLUGIN / "wrist_camera_arm.urdf")
      .lexically_normal();
}

nlohmann::json pose_json(const Eigen::Isometry3d& t) {
  const Eigen::Quaterniond q(t.linear());
  const Eigen::Vector3d p = t.translation();
  return {{"position", {p.x(), p.y(), p.z()}}, {"quaternion_wxyz", {q.w(), q.x(), q.y(), q.z()}}};
}

}  // namespace

std::vector<double> values(const Eigen::VectorXd& v) { return {v.data(), v.data() + v.size()}; }

ArmComponent::ArmComponent(fba::Context& ctx)
    : ctx_(ctx),
      model_(ctx(kUrdf).empty() ? default_urdf() : ctx(kUrdf), ctx(kBaseLink), ctx(kCameraLink)),
      publish_initial_(ctx(kPublishInitial)) {
  ik_.position_tolerance = ctx(kPositionTolerance);
  ik_.orientation_tolerance = ctx(kOrientationTolerance);
  ik_.attempts = ctx(kAttempts);
}

std::string ArmComponent::goal_of(const Request& r, const Eigen::VectorXd& from, Eigen::VectorXd& goal,
                                  nlohmann::json& target) const {
  if (const auto* pose = std::get_if<fba::Pose>(&r)) {
    target = {{"pose", pose_json(pose->world_from_frame)}};
    const auto ik = model_.inverse(pose->world_from_frame, from, ik_);
    if (!ik.ok) return ik.why;
    goal = ik.joints;
    return {};
  }
  const auto& js = std::get<fba::JointState>(r);
  target = {{"names", js.names}, {"positions", js.positions}};
  return joint_goal(js, from, goal);
}

std::string ArmComponent::joint_goal(const fba::JointState& js, const Eigen::VectorXd& from,
                                     Eigen::VectorXd& goal) const {
  const auto& joints = model_.joint_names();
  goal = from;
  if (js.names.empty()) {
    if (js.positions.size() != joints.size())
      return std::to_string(js.positions.size()) + " positions without names; the arm has " +
             std::to_string(joints.size()) + " joints (" + names() + ")";
    goal = Eigen::Map<const Eigen::VectorXd>(js.positions.data(), static_cast<Eigen::Index>(js.positions.size()));
  } else {
    if (js.names.size() != js.positions.size())
      return std::to_string(js.names.size()) + " names but " + std::to_string(js.positions.size()) + " positions";
    for (std::size_t i = 0; i < js.names.size(); ++i) {
      const auto it = std::find(joints.begin(), joints.end(), js.names[i]);
      if (it == joints.end()) return "no joint '" + js.names[i] + "'; the arm's joints are " + names();
      goal(it - joints.begin()) = js.positions[i];
    }
  }
  return model_.limit_violation(goal);
}

void ArmComponent::refuse(const nlohmann::json& target, const std::string& why) {
  ctx_.log().warn("unreachable target {}: {}", target.dump(), why);
  ctx_.emit(kUnreachable, nlohmann::json{{"target", target}, {"reason", why}}.dump());
}

void ArmComponent::publish_state(std::vector<double> positions, std::vector<double> velocities,
                                 std::int64_t stamp_ns) {
  fba::JointState s;
  s.names = model_.joint_names();
  s.positions = std::move(positions);
  s.velocities = std::move(velocities);
  s.stamp = static_cast<double>(stamp_ns) * 1e-9;
  ctx_(kJointState).emit(std::move(s), stamp_ns);
}

void ArmComponent::publish_initial(const Eigen::VectorXd& q, std::vector<double> velocities, std::int64_t stamp_ns) {
  if (!publish_initial_) return;
  publish_initial_ = false;
  publish_state(values(q), std::move(velocities), stamp_ns);
  ctx_(kCameraPose).emit(pose_at(q, stamp_ns), stamp_ns);
}

void ArmComponent::arrive(const Eigen::VectorXd& q, std::int64_t stamp_ns) {
  const fba::Pose pose = pose_at(q, stamp_ns);
  ctx_(kCameraPose).emit(pose, stamp_ns);
  ctx_.emit(kArrived, nlohmann::json{{"pose", pose_json(pose.world_from_frame)}, {"joints", values(q)}}.dump());
}

fba::Pose ArmComponent::pose_at(const Eigen::VectorXd& q, std::int64_t stamp_ns) const {
  fba::Pose p;
  p.world_from_frame = model_.forward(q);
  p.stamp = static_cast<double>(stamp_ns) * 1e-9;
  return p;
}

std::string ArmComponent::names() const {
  std::string s;
  for (const auto& n : model_.joint_names()) s += (s.empty() ? "" : ", ") + n;
  return s;
}

}  // namespace fba::arm
