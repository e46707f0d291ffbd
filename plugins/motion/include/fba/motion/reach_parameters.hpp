// The reach planner's parameters as components declare them: motion.reach_planner, which plans
// the arm's motion to a grasp, and grasp.synthesis, which passes over the grasps the arm cannot
// reach (ReachPlanner::reachable). Declared once here, with their names, defaults and ranges, so
// that the two components read the same robot and cannot disagree on what is reachable; a task
// that changes one sets it on both.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include <fba/component.hpp>
#include <fba/types/joint_state.hpp>

#include "arm_model.hpp"
#include "fba/motion/reach_planner.hpp"

namespace fba::motion {

// The project's arm, wrist_camera_arm.urdf, where the build and the install put it: at the same
// place relative to the plugin (the file this code is linked into) as sim.arm finds it.
std::filesystem::path default_urdf();

struct ReachParameters {
  static constexpr fba::Param<std::filesystem::path> kUrdf{
      "urdf", "", "the arm's URDF (kinematics, limits, collision shapes); empty: the project's wrist_camera_arm.urdf"};
  static constexpr fba::Param<std::string> kBaseLink{"base_link", "world", "the frame grasps are given in"};
  static constexpr fba::Param<std::string> kFlangeLink{"flange_link", "flange", "the link the hand is mounted on"};
  static inline const auto kFlangeToPalm = fba::Param<std::vector<double>>(
      "flange_to_palm", std::vector<double>{0, 0, 0.075, 0, 0, 0},
      "the palm's frame on the flange: [x, y, z] in metres and [roll, pitch, yaw] in radians (the default: the palm's back 3 cm "
      "out along the flange's axis, past the wrist camera)")
      .size({6});
  static constexpr auto kStandoff =
      fba::Param<double>("standoff", 0.05, "metres back along the approach where the path ends and the straight approach begins").range(0, 0.5);
  static constexpr auto kLiftHeight = fba::Param<double>("lift_height", 0.1, "metres, straight up").range(0, 0.5);
  static constexpr auto kContactAllowance = fba::Param<double>(
      "contact_allowance", 0.02, "metres around each contact where the fingers may touch the model (about to touch the object)")
      .range(0, 0.1);
  static constexpr auto kMaxBackout = fba::Param<double>(
      "max_backout", 0.2,
      "metres: a start whose open hand is in the model (space the views have not carved yet) backs out along the flange's axis "
      "at most this far until clear; 0: such a start is refused").range(0, 0.5);
  static constexpr auto kSeed =
      fba::Param<int>("seed", 1, "seed of the path search and the IK's random starts: the same plan on every run").range(1, 2147483647);
  static constexpr auto kIkAttempts =
      fba::Param<int>("ik_attempts", 32, "IK starts for the pregrasp: the current joints, then random ones").range(1, 10000);

  // Declares them on a component's spec.
  static fba::Spec& add(fba::Spec& spec) {
    return spec.add(kUrdf, kBaseLink, kFlangeLink, kFlangeToPalm, kStandoff, kLiftHeight, kContactAllowance, kMaxBackout, kSeed,
                    kIkAttempts);
  }
  // `p` with these parameters' values.
  static ReachParams read(const fba::Context& ctx, ReachParams p = {}) {
    const std::vector<double> f = ctx(kFlangeToPalm);
    p.flange_from_palm = Eigen::Translation3d(f[0], f[1], f[2]) * Eigen::AngleAxisd(f[5], Eigen::Vector3d::UnitZ()) *
                         Eigen::AngleAxisd(f[4], Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(f[3], Eigen::Vector3d::UnitX());
    p.standoff = ctx(kStandoff);
    p.lift_height = ctx(kLiftHeight);
    p.contact_allowance = ctx(kContactAllowance);
    p.max_backout = ctx(kMaxBackout);
    p.seed = static_cast<std::uint32_t>(ctx(kSeed));
    p.ik_attempts = ctx(kIkAttempts);
    return p;
  }
  // The planner they describe, the rest of `p` as given. Throws as ReachPlanner's constructor.
  static ReachPlanner planner(const fba::Context& ctx, const ReachParams& p = {}) {
    return ReachPlanner(ctx(kUrdf).empty() ? default_urdf() : ctx(kUrdf), read(ctx, p), ctx(kBaseLink), ctx(kFlangeLink));
  }
};

// A joint state in the arm's joint order: by name, or as given when it has no names (then it must
// have as many positions as the arm has joints). nullopt with `why` when a joint is missing.
std::optional<Eigen::VectorXd> arm_joints(const arm::ArmModel& arm, const fba::JointState& state, std::string& why);

}  // namespace fba::motion
