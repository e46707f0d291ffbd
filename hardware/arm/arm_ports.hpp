// The ports and events of the task's arm, declared once for both twins: sim.arm (simulated) and
// hw.canopen_arm (the real arm over CANopen) inherit them, so a task can swap one for the other
// and their specs cannot drift apart.
#pragma once

#include <fba/spec.hpp>
#include <fba/types/joint_state.hpp>
#include <fba/types/joint_trajectory.hpp>
#include <fba/types/pose.hpp>
#include <fba/types/robot_description.hpp>

namespace fba::arm {

struct ArmPorts {
  static constexpr fba::OptionalIn<fba::Pose> kTarget{
      "target", "move the camera to this pose (world_from_frame of the camera link, in base_link's frame)"};
  static constexpr fba::OptionalIn<fba::JointState> kJointTarget{
      "joint_target", "move the joints to these positions (by name, or all in the arm's order when names are empty)"};
  static constexpr fba::OptionalIn<fba::JointTrajectory> kTrajectory{
      "trajectory",
      "follow this timed trajectory from where the arm stands, every joint at each waypoint at its time (the "
      "trajectory's clock starts when it arrives); refused with 'unreachable' when its joints are not the arm's, a "
      "waypoint is outside the position or velocity limits, it does not start where the arm stands, or the arm is moving"};
  static constexpr fba::Out<fba::JointState> kJointState{"joint_state",
                                                         "the joints, at `rate` while the arm moves and when it stops"};
  static constexpr fba::Out<fba::Pose> kCameraPose{
      "camera_pose",
      "the camera's pose where each motion ends (and where the arm starts): wire it to the camera's pose"};
  static constexpr fba::Out<fba::RobotDescription> kRobot{
      "robot", "the robot this arm moves, once, at the first tick: its URDF with the measured transforms in place (base_pose, "
      "flange_to_palm, flange_to_camera), which a live view draws"};
  static constexpr fba::EventOut kArrived{
      "arrived", "a motion or a trajectory ended; payload: the camera pose and the joints, JSON"};
  static constexpr fba::EventOut kUnreachable{
      "unreachable",
      "a target or a trajectory was refused (no IK solution within the limits and tolerances, a joint outside its "
      "limits, a trajectory that does not fit the arm); payload: the target and why, JSON"};
};

}  // namespace fba::arm
