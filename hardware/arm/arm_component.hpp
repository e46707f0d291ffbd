// What the task's two arms do alike, written once: sim.arm (simulated) and hw.canopen_arm (the real
// arm over CANopen) derive from ArmComponent. It holds the arm's model from the robot's parameters,
// turns a target into joint goals, and publishes the joint states, the camera pose and the
// 'arrived' and 'unreachable' events; each twin adds how its joints move.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

#include <fba/component.hpp>

#include "arm_model.hpp"
#include "arm_ports.hpp"
#include "robot_parameters.hpp"

#ifdef FBA_ARM_COLLISION
#include "fba/motion/robot_collision.hpp"
#endif

namespace fba::arm {

// A trajectory (fba.JointTrajectory) as an arm follows it: its waypoints in the arm's joint order,
// checked against the arm (ArmComponent::path_of), positions in between on straight lines.
class TimedPath {
 public:
  double duration() const { return times_.empty() ? 0.0 : times_.back(); }  // s
  const Eigen::VectorXd& start() const { return positions_.front(); }
  const Eigen::VectorXd& goal() const { return positions_.back(); }
  std::size_t size() const { return times_.size(); }
  // Positions and velocities at time t (s from the first waypoint; clamped to [0, duration]): on the
  // straight line between the waypoints around t, at that segment's velocity (0 at the ends).
  void sample(double t, Eigen::VectorXd& positions, Eigen::VectorXd& velocities) const;

 private:
  friend class ArmComponent;
  std::vector<double> times_;
  std::vector<Eigen::VectorXd> positions_;
};

class ArmComponent : public fba::Component, public ArmPorts {
 public:
  // The robot (urdf, base_pose, flange_to_palm, flange_to_camera): its kinematics and joint limits,
  // where the camera sits for the camera pose, where the hand sits for the collision check.
  using Robot = RobotParameters;
  static constexpr fba::Param<std::string> kBaseLink{"base_link", "world", "the frame target poses are given in"};
  static constexpr fba::Param<std::string> kCameraLink{"camera_link", "camera",
                                                       "the camera's optical frame (z forward, x right, y down)"};
  static constexpr auto kSpeed =
      fba::Param<double>("speed_scale", 0.5, "share of each joint's URDF velocity limit used by motions")
          .range(0.01, 1.0);
  static constexpr auto kAcceleration =
      fba::Param<double>("acceleration", 3.0, "joint acceleration limit, rad/s^2 (m/s^2), every joint")
          .range(0.01, 100.0);
  static constexpr auto kPositionTolerance =
      fba::Param<double>("position_tolerance", 1e-4, "how close IK must bring the camera to a target, m")
          .range(1e-9, 0.1);
  static constexpr auto kOrientationTolerance =
      fba::Param<double>("orientation_tolerance", 1e-3, "how close IK must turn the camera to a target, rad")
          .range(1e-9, 0.5);
  static constexpr auto kAttempts =
      fba::Param<int>("ik_attempts", 32, "IK starts: the current joints, then random seeds").range(1, 10000);
  static constexpr auto kInitialCameraPose = fba::Param<bool>(
      "initial_camera_pose", true,
      "publish the camera pose where the arm starts, at the first tick, so that a camera wired to camera_pose takes a picture "
      "there (off where a planner asks for every view). The joint state there goes out whatever this says: a state, not a view");
  static constexpr fba::Param<bool> kCollisionCheck{
      "collision_check", true,
      "a target's IK solution must keep the arm, its camera and the hand on its flange (the URDF's collision shapes, the hand "
      "open) off the arm itself and the table: among the attempts, the nearest such solution is taken, so a view is reached "
      "with the hand clear of the forearm; off: any solution within the limits"};

 protected:
  using Request = std::variant<fba::Pose, fba::JointState>;

  explicit ArmComponent(fba::Context& ctx);

  // The joint goal a request asks for from `from` (IK for a pose), and the request as JSON for the
  // events; returns why it cannot be had, or "" when `goal` is set.
  std::string goal_of(const Request& r, const Eigen::VectorXd& from, Eigen::VectorXd& goal,
                      nlohmann::json& target) const;
  // A refused target: logged, and the 'unreachable' event with the target and the reason.
  void refuse(const nlohmann::json& target, const std::string& why);

  // How far a trajectory's first waypoint may be from where the arm stands, rad (m), each joint.
  static constexpr double kStartTolerance = 0.01;
  // The trajectory as the arm follows it, checked: its joints are the arm's (each once, any order),
  // its times start at 0 and increase, every waypoint is within the joints' position limits, no
  // joint moves faster between two waypoints than its URDF velocity limit, and it starts within
  // kStartTolerance of `from`. Returns why not, or "" when `path` is set; `target` is the
  // trajectory as JSON for the events.
  std::string path_of(const fba::JointTrajectory& t, const Eigen::VectorXd& from, TimedPath& path,
                      nlohmann::json& target) const;

  void publish_state(std::vector<double> positions, std::vector<double> velocities, std::int64_t stamp_ns);
  // At the first tick: the robot, the joints, and (unless initial_camera_pose is off) the camera pose.
  void publish_initial(const Eigen::VectorXd& q, std::vector<double> velocities, std::int64_t stamp_ns);
  // Where a motion ended: the camera pose, and 'arrived' with it and the joints.
  void arrive(const Eigen::VectorXd& q, std::int64_t stamp_ns);

  // "shoulder_pan_joint, shoulder_lift_joint, ...": for messages.
  std::string names() const;

  fba::Context& ctx_;
  // The robot as the parameters describe it, the measured origins in place; read once.
  const RobotDescription robot_;
  const ArmModel model_;
  IkOptions ik_;
#ifdef FBA_ARM_COLLISION
  // The checks behind ik_.accept, on the chain to the flange (which they refer to): null when
  // collision_check is off or the URDF has no palm.
  std::unique_ptr<ArmModel> to_flange_;
  std::unique_ptr<fba::motion::RobotCollision> collision_;
#endif

 private:
  // The links the collision check reads: the hand is mounted on the flange, at the palm.
  static constexpr const char* kFlangeLink = "flange";
  static constexpr const char* kPalmLink = "palm";
  // Sets ik_.accept to the robot's collision check (collision_check).
  void check_collisions(const fba::Context& ctx);

  fba::Pose pose_at(const Eigen::VectorXd& q, std::int64_t stamp_ns) const;
  std::string joint_goal(const fba::JointState& js, const Eigen::VectorXd& from, Eigen::VectorXd& goal) const;

  bool initial_published_ = false;
  const bool initial_camera_pose_;
};

// The vector's values as a std::vector, for JointState and JSON.
std::vector<double> values(const Eigen::VectorXd& v);

}  // namespace fba::arm
