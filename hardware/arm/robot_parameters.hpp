// The robot's parameters, declared once for every component that reads the robot: the one URDF
// (arm, wrist camera, hand on the flange) and the three transforms measured on each real robot
// (docs/hardware.md, "One robot, described once"). sim.arm and hw.canopen_arm (their kinematics and
// camera pose), motion.reach_planner and grasp.synthesis (where the palm sits, the arm's reach),
// grasp.exploration_planner (which views the arm reaches) and sim.hand (the MuJoCo world) declare
// them with add() and read the description with read(), so that a measured transform, set once as
// a task parameter, moves the same robot in all of them.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <fba/component.hpp>
#include <fba/types/robot_description.hpp>

#include "arm_model.hpp"

namespace fba::arm {

// The project's robot, wrist_camera_arm.urdf, where the build and the install put it: at the same
// place relative to the plugins' folder, found from the plugin this code is linked into.
std::filesystem::path default_urdf();

// The robot's URDF text with the measured origins in place, and what to call it in messages (the
// file, and which of its origins the parameters replaced): the data type the arm publishes.
using RobotDescription = fba::RobotDescription;

struct RobotParameters {
  static constexpr fba::Param<std::filesystem::path> kUrdf{
      "urdf", "",
      "the robot's URDF: the arm (kinematics, limits, collision shapes), its wrist camera and the hand on its flange; empty: the "
      "project's wrist_camera_arm.urdf (a UR5-like 6R arm), installed beside the plugins"};
  // Each in place of its fixed joint's origin in the URDF (with_fixed_joint_origins).
  static inline const auto kBasePose = fba::Param<std::vector<double>>(
      "base_pose", std::vector<double>{},
      "the arm's base on the table, measured (the URDF's joint world_to_base): [x, y, z] m, [roll, pitch, yaw] rad; empty: the URDF's")
      .size({0, 6});
  static inline const auto kFlangeToPalm = fba::Param<std::vector<double>>(
      "flange_to_palm", std::vector<double>{},
      "the hand's palm on the flange, measured (the URDF's joint flange_to_palm): [x, y, z] m, [roll, pitch, yaw] rad; empty: the "
      "URDF's")
      .size({0, 6});
  static inline const auto kFlangeToCamera = fba::Param<std::vector<double>>(
      "flange_to_camera", std::vector<double>{},
      "the camera on the flange, measured by hand-eye calibration (the URDF's joint flange_to_camera): [x, y, z] m, [roll, pitch, "
      "yaw] rad; empty: the URDF's")
      .size({0, 6});

  // The URDF joints whose origins they replace.
  static constexpr const char* kBaseJoint = "world_to_base";
  static constexpr const char* kPalmJoint = "flange_to_palm";
  static constexpr const char* kCameraJoint = "flange_to_camera";

  // Declares them on a component's spec.
  static fba::Spec& add(fba::Spec& spec) { return spec.add(kUrdf, kBasePose, kFlangeToPalm, kFlangeToCamera); }

  // The URDF (urdf, else default_urdf()) with the measured origins in place. Throws ArmModelError
  // when the file cannot be read or a measured joint is missing or not fixed, and
  // std::invalid_argument for a transform that is not six finite numbers; each names the parameter.
  static RobotDescription read(const fba::ParamValues& params);
  static RobotDescription read(const fba::Context& ctx) { return read(ctx.params()); }
};

}  // namespace fba::arm
