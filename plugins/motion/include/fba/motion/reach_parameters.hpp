// The reach planner's parameters as components declare them: motion.reach_planner, which plans
// the arm's motion to a grasp, and grasp.synthesis, which passes over the grasps the arm cannot
// reach (ReachPlanner::reachable, and plan() for the one it selects). Declared once here, with their names, defaults and ranges, so
// that the two components read the same robot and cannot disagree on what is reachable; a task
// that changes one sets it on both. The robot itself (urdf, base_pose, flange_to_palm,
// flange_to_camera) is arm::RobotParameters, which every component that reads the robot declares:
// the palm sits on the flange where the URDF's joint flange_to_palm puts it, or where the
// parameter flange_to_palm measured it.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include <fba/component.hpp>
#include <fba/types/joint_state.hpp>

#include "arm_model.hpp"
#include "fba/motion/reach_planner.hpp"
#include "fba/motion/robot_collision.hpp"
#include "robot_parameters.hpp"

namespace fba::motion {

struct ReachParameters {
  static constexpr fba::Param<std::string> kBaseLink{"base_link", "world", "the frame grasps are given in"};
  static constexpr fba::Param<std::string> kFlangeLink{"flange_link", "flange", "the link the hand is mounted on"};
  static constexpr auto kStandoff =
      fba::Param<double>("standoff", reach_defaults::kStandoff, "metres back along the approach where the path ends and the straight approach begins").range(0, 0.5);
  static constexpr auto kLiftHeight = fba::Param<double>("lift_height", reach_defaults::kLiftHeight, "metres, straight up").range(0, 0.5);
  static constexpr auto kContactAllowance = fba::Param<double>(
      "contact_allowance", reach_defaults::kContactAllowance,
      "metres around each contact where the fingers may touch the model (about to touch the object: the model's voxel "
      "staircase there); wider lets fingers meet the object on the way in (docs/results.md, \"The grasp loop in simulation\")")
      .range(0, 0.1);
  static constexpr auto kMaxBackout = fba::Param<double>(
      "max_backout", reach_defaults::kMaxBackout,
      "metres: a start whose open hand is in the model (space the views have not carved yet) backs out along the flange's axis, "
      "else straight up, at most this far until clear, else by joints alone (each moved a little about where it stands); 0: such a start "
      "is refused").range(0, 0.5);
  static constexpr auto kSeed =
      fba::Param<int>("seed", static_cast<int>(reach_defaults::kSeed), "seed of the path search and the IK's random starts: the same plan on every run").range(1, 2147483647);
  static constexpr auto kIkAttempts =
      fba::Param<int>("ik_attempts", reach_defaults::kIkAttempts, "IK starts for the pregrasp: the current joints, then random ones").range(1, 10000);
  static constexpr auto kPlanningTime =
      fba::Param<double>("planning_time", reach_defaults::kPlanningTime, "seconds of wall time the collision-free path search may take at most: a guard "
                         "(path_checks ends it first, at the same point on any machine)").range(0.001, 600);
  static constexpr auto kPathChecks =
      fba::Param<std::int64_t>("path_checks", static_cast<std::int64_t>(reach_defaults::kPathChecks), "poses the collision-free path search may check before it gives up: "
                                                     "its bound, the same on a loaded machine as on an idle one")
          .range(1, 10'000'000);

  // Declares them, with the robot's, on a component's spec.
  static fba::Spec& add(fba::Spec& spec) {
    arm::RobotParameters::add(spec);
    return spec.add(kBaseLink, kFlangeLink, kStandoff, kLiftHeight, kContactAllowance, kMaxBackout, kSeed, kIkAttempts, kPlanningTime,
                    kPathChecks);
  }
  // `p` with these parameters' values, the palm on the flange where `robot` places it.
  static ReachParams read(const fba::Context& ctx, const arm::RobotDescription& robot, ReachParams p = {}) {
    p.flange_from_palm = urdf_flange_from_palm(robot.urdf, robot.name, ctx(kBaseLink), ctx(kFlangeLink));
    p.standoff = ctx(kStandoff);
    p.lift_height = ctx(kLiftHeight);
    p.contact_allowance = ctx(kContactAllowance);
    p.max_backout = ctx(kMaxBackout);
    p.seed = static_cast<std::uint32_t>(ctx(kSeed));
    p.ik_attempts = ctx(kIkAttempts);
    p.planning_time = ctx(kPlanningTime);
    p.path_checks = static_cast<std::size_t>(ctx(kPathChecks));
    return p;
  }
  // The planner they describe, the rest of `p` as given. Throws as ReachPlanner's constructor, and
  // arm::RobotParameters::read.
  static ReachPlanner planner(const fba::Context& ctx, const arm::RobotDescription& robot, const ReachParams& p = {}) {
    return ReachPlanner(arm::ArmModel::from_string(robot.urdf, robot.name, ctx(kBaseLink), ctx(kFlangeLink)), read(ctx, robot, p));
  }
  static ReachPlanner planner(const fba::Context& ctx, const ReachParams& p = {}) {
    return planner(ctx, arm::RobotParameters::read(ctx), p);
  }
};

// A joint state in the arm's joint order: by name, or as given when it has no names (then it must
// have as many positions as the arm has joints). nullopt with `why` when a joint is missing.
std::optional<Eigen::VectorXd> arm_joints(const arm::ArmModel& arm, const fba::JointState& state, std::string& why);

// Whether the arm stands still in `state`: every velocity it gives below 1e-3 rad/s (none given: a
// state from a source that does not measure them, taken as still). A plan or a move starts only
// from there: from a moving arm's joints it starts where the arm no longer is.
bool at_rest(const fba::JointState& state);

}  // namespace fba::motion
