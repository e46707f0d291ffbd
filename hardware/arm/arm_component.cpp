#include "arm_component.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>

#include <fba/types/pose_json.hpp>

namespace fba::arm {

std::vector<double> values(const Eigen::VectorXd& v) { return {v.data(), v.data() + v.size()}; }

void TimedPath::sample(double t, Eigen::VectorXd& positions, Eigen::VectorXd& velocities) const {
  velocities = Eigen::VectorXd::Zero(positions_.front().size());
  if (times_.size() < 2 || !(t > 0)) {
    positions = positions_.front();
    return;
  }
  if (t >= times_.back()) {
    positions = positions_.back();
    return;
  }
  const std::size_t k = static_cast<std::size_t>(std::upper_bound(times_.begin(), times_.end(), t) - times_.begin()) - 1;
  const double dt = times_[k + 1] - times_[k];
  velocities = (positions_[k + 1] - positions_[k]) / dt;
  positions = positions_[k] + velocities * (t - times_[k]);
}

std::string ArmComponent::path_of(const fba::JointTrajectory& t, const Eigen::VectorXd& from, TimedPath& path,
                                  nlohmann::json& target) const {
  const auto& joints = model_.joint_names();
  const std::size_t n = joints.size();
  target = {{"trajectory",
             {{"joints", t.names},
              {"waypoints", t.points.size()},
              {"duration_s", t.points.empty() ? 0.0 : t.points.back().time}}}};
  auto text = [](double v) {
    std::ostringstream s;
    s << v;
    return s.str();
  };
  // Its joints, each to its place in the arm's order.
  std::vector<std::size_t> place(t.names.size());
  std::set<std::string> seen;
  for (std::size_t i = 0; i < t.names.size(); ++i) {
    const auto it = std::find(joints.begin(), joints.end(), t.names[i]);
    if (it == joints.end()) return "the trajectory's joint '" + t.names[i] + "' is not one of the arm's (" + names() + ")";
    if (!seen.insert(t.names[i]).second) return "the trajectory names joint '" + t.names[i] + "' twice";
    place[i] = static_cast<std::size_t>(it - joints.begin());
  }
  for (const auto& j : joints)
    if (!seen.count(j)) return "the trajectory has no joint '" + j + "'; it must move every joint of the arm (" + names() + ")";
  if (t.points.empty()) return "the trajectory has no waypoint";
  path.times_.clear();
  path.positions_.clear();
  for (std::size_t k = 0; k < t.points.size(); ++k) {
    const auto& p = t.points[k];
    const std::string at = "waypoint " + std::to_string(k) + " (at " + text(p.time) + " s)";
    if (p.positions.size() != n)
      return at + " has " + std::to_string(p.positions.size()) + " positions for " + std::to_string(n) + " joints";
    if (!std::isfinite(p.time) || (k == 0 && p.time != 0) || (k > 0 && !(p.time > path.times_.back())))
      return at + ": the times must start at 0 and increase";
    Eigen::VectorXd q(static_cast<Eigen::Index>(n));
    for (std::size_t i = 0; i < n; ++i) q(static_cast<Eigen::Index>(place[i])) = p.positions[i];
    if (!q.allFinite()) return at + " has a position that is not a number";
    if (const std::string bad = model_.limit_violation(q); !bad.empty()) return at + ": " + bad;
    if (k > 0) {
      const double dt = p.time - path.times_.back();
      for (std::size_t j = 0; j < n; ++j) {
        const auto jj = static_cast<Eigen::Index>(j);
        const double v = std::abs(q(jj) - path.positions_.back()(jj)) / dt, limit = model_.limits()[j].velocity;
        if (limit > 0 && v > limit * (1 + 1e-6) + 1e-9)
          return at + ": joint '" + joints[j] + "' would move at " + text(v) + " rad/s from the waypoint before, beyond its limit of " +
                 text(limit) + " rad/s";
      }
    }
    path.times_.push_back(p.time);
    path.positions_.push_back(std::move(q));
  }
  for (std::size_t j = 0; j < n; ++j) {
    const auto jj = static_cast<Eigen::Index>(j);
    if (std::abs(path.positions_.front()(jj) - from(jj)) > kStartTolerance)
      return "the trajectory starts with joint '" + joints[j] + "' at " + text(path.positions_.front()(jj)) +
             " rad, but the arm stands at " + text(from(jj)) + " rad (more than " + text(kStartTolerance) + " apart)";
  }
  return {};
}

ArmComponent::ArmComponent(fba::Context& ctx)
    : ctx_(ctx),
      robot_(Robot::read(ctx)),
      model_(ArmModel::from_string(robot_.urdf, robot_.name, ctx(kBaseLink), ctx(kCameraLink))),
      initial_camera_pose_(ctx(kInitialCameraPose)) {
  ik_.position_tolerance = ctx(kPositionTolerance);
  ik_.orientation_tolerance = ctx(kOrientationTolerance);
  ik_.attempts = ctx(kAttempts);
  if (ctx(kCollisionCheck)) check_collisions(ctx);
}

void ArmComponent::check_collisions(const fba::Context& ctx) {
#ifdef FBA_ARM_COLLISION
  Eigen::Isometry3d flange_from_palm;
  try {
    flange_from_palm = fba::motion::urdf_flange_from_palm(robot_.urdf, robot_.name, ctx(kBaseLink), kFlangeLink, kPalmLink);
  } catch (const ArmModelError&) {
    ctx.log().info("no '{}' link after '{}' in {}: IK solutions are not checked for collisions (the hand's place is needed)",
                   kPalmLink, kFlangeLink, robot_.name);
    return;
  }
  to_flange_ = std::make_unique<ArmModel>(ArmModel::from_string(robot_.urdf, robot_.name, ctx(kBaseLink), kFlangeLink));
  collision_ = std::make_unique<fba::motion::RobotCollision>(*to_flange_, flange_from_palm);
  ik_.accept = [c = collision_.get()](const Eigen::VectorXd& q) { return c->collision(q); };
#else
  ctx.log().warn("built without FCL (plugins/motion left out): IK solutions are not checked for collisions");
#endif
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
  if (initial_published_) return;
  initial_published_ = true;
  ctx_(kRobot).emit(robot_, stamp_ns);
  publish_state(values(q), std::move(velocities), stamp_ns);
  if (initial_camera_pose_) ctx_(kCameraPose).emit(pose_at(q, stamp_ns), stamp_ns);
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
