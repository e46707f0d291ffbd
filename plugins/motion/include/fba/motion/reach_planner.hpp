// Reach planning, the motor stage: from a selected grasp and the carved model, what MoveIt would
// compute for a ROS arm. The palm's pregrasp on the grasp's approach line (hand_placement.hpp),
// inverse kinematics for the flange there (KDL, several seeds, the solution nearest the current
// joints), a collision-free joint path from the current joints to the standoff (OMPL's
// RRT-Connect, then shortcut), the straight approach, the close, the straight lift, the hold and
// the retreat (the object put back, the hand opened, the way in backed out), timed within the
// URDF's velocity limits, with the hand's commands in order. Collisions (robot_collision.hpp):
// the arm, the camera and the hand against the table, the arm itself and the model, whose
// occupied and not-yet-carved leaves are obstacles until the fingers close.
//
// A start whose hand is in the model (at a view pose, the open hand reaches into space the views
// have not carved yet) first backs out along the flange's axis, away from where the hand points,
// until clear: the plan begins with that retreat.
//
// A refusal says which step failed and why, so that grasp synthesis can pass over grasps the arm
// cannot take and count the reasons: reachable() is the cheap check (everything but the path
// search), plan() the whole plan.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "arm_model.hpp"
#include "fba/motion/model_obstacles.hpp"
#include "fba/types/grasp.hpp"
#include "fba/types/hand_command.hpp"
#include "fba/types/joint_trajectory.hpp"
#include "fba/types/octree.hpp"

namespace fba::motion {

// The defaults of ReachParams that reach_parameters.hpp's component parameters declare too.
namespace reach_defaults {
inline constexpr double kStandoff = 0.05;
inline constexpr double kLiftHeight = 0.10;
inline constexpr double kContactAllowance = 0.005;
inline constexpr double kMaxBackout = 0.2;
inline constexpr std::uint32_t kSeed = 1;
inline constexpr int kIkAttempts = 32;
inline constexpr double kPlanningTime = 30;
inline constexpr std::size_t kPathChecks = 20000;
}  // namespace reach_defaults

struct ReachParams {
  // Where the palm sits on the flange (the flange's frame: z out of it).
  Eigen::Isometry3d flange_from_palm = Eigen::Isometry3d(Eigen::Translation3d(0, 0, 0.075));
  double clearance = 0.01;       // m between each pad and its contact at the pregrasp, at least
  double standoff = reach_defaults::kStandoff;        // m back along the approach from the grasp: where the path ends
  double lift_height = reach_defaults::kLiftHeight;   // m, straight up
  double hold_s = 2.0;           // s the arm holds still at the top of the lift
  double hand_s = 1.0;           // s the arm stands still while the hand opens or closes
  double finger_force = 15.0;    // N at each pad when closing (the Robotiq 3-Finger grips with 15 to 60)
  bool retreat = true;           // after the hold: put the object back, open, back out to the standoff
  // The fingers may touch the model within this distance of their contacts (the model is the
  // object's visual hull: near a contact the finger is about to touch the object).
  double contact_allowance = reach_defaults::kContactAllowance;
  std::size_t path_checks = reach_defaults::kPathChecks;  // poses the path search may check: its deterministic bound
  double planning_time = reach_defaults::kPlanningTime;   // s: a guard on the path search's wall time
  std::uint32_t seed = reach_defaults::kSeed;  // OMPL's random numbers (and the IK's and the jiggle's): the same plan every run
  int ik_attempts = reach_defaults::kIkAttempts;  // IK starts: the current joints, then random ones within the limits
  double cartesian_step = 0.01;  // m between the IK solutions along a straight line
  double max_joint_step = 0.3;   // rad: a larger jump between two of them is a flip, not a line
  double collision_step = 0.02;  // rad: motions are checked at poses this far apart (joint space, Euclidean)
  double speed_scale = 0.5;      // share of each joint's URDF velocity limit used
  double acceleration = 3.0;     // rad/s^2, every joint
  double sample_period = 0.02;   // s between the trajectory's waypoints (and at each segment's ends)
  // m: a start whose hand touches the model (but not the table or the arm) backs out along the
  // flange's -z axis (the wrist camera's line of sight, backwards) at most this far, in
  // cartesian_step steps, each an IK solution, until clear of the model. 0: such a start is refused.
  double max_backout = reach_defaults::kMaxBackout;
  // Where neither line backs out (the arm at the end of its reach), joint positions drawn around
  // the current ones, each joint within up to jiggle_share of its range (MoveIt's
  // FixStartStateCollision, its jiggle_fraction 0.05 and 100 draws). 0 draws: not tried.
  std::size_t jiggle_draws = 100;
  double jiggle_share = 0.05;
  // The pregrasp's IK: the first solution found from which the straight approach and lift work,
  // rather than the one nearest the current joints among all ik_attempts. A yes-or-no check
  // (grasp synthesis's) at a fraction of the cost: the lines are then checked for one solution, not
  // for every one the attempts find. Whatever it accepts, the nearest search accepts too.
  bool first_solution = false;
  // Whether reachable() checks the current joints (and backs out of the model): false judges the
  // grasp alone, whatever the arm's pose now (the pregrasp's IK still starts from the current
  // joints). Grasp synthesis asks so, since no choice of grasp clears a start that cannot be. Not
  // for plan(), whose path must start free.
  bool check_start = true;
};

// Why a grasp was refused, for counting.
enum class Refusal {
  None,
  Hand,       // the hand cannot take it (contacts too far apart, a bad grasp)
  Table,      // the hand at the grasp, its pregrasp or the lift would be in the table
  Ik,         // no IK solution within the joint limits for the pregrasp
  Collision,  // every IK solution for the pregrasp collides
  Approach,   // the straight approach has no IK solution or collides
  Lift,       // the straight lift has no IK solution or collides
  Start,      // the current joints collide with the table or the arm itself (with the hand opened for the
              // pregrasp), or with the model and backing out does not clear them
  Path,       // no collision-free path to the pregrasp within the time limit
};
const char* to_string(Refusal r);

struct ReachFigures {
  int ik_attempts = 0;             // IK solver starts, the pregrasp's and the lines' steps
  double planning_s = 0;           // wall time of the path search
  double path_length = 0;          // rad: the path's length in joint space (Euclidean)
  std::size_t path_waypoints = 0;  // after shortcutting
  bool direct = false;             // the straight joint-space line was free: no search needed
  std::size_t collision_checks = 0;
  double backout = 0;              // m the start backed out of the model along the flange's axis
};

// One step of the plan on the trajectory's clock.
struct ReachStep {
  std::string name;  // "plan" (the back-out, the hand opens, the path), "approach", "close", "lift", "hold", "retreat"
  double start_s = 0;
  double end_s = 0;
};

struct ReachPlan {
  bool ok = false;
  Refusal refusal = Refusal::None;
  std::string why;  // when !ok
  // When !ok: the refusal is the hand or the arm meeting the carved model (occupied or not yet
  // carved space), which more views may clear, rather than the table, the arm or its reach.
  bool model_blocked = false;

  // The poses (world) and joint positions along the plan.
  Eigen::Isometry3d pregrasp_palm = Eigen::Isometry3d::Identity();  // at the standoff
  Eigen::Isometry3d grasp_palm = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d lift_palm = Eigen::Isometry3d::Identity();
  Eigen::VectorXd pregrasp_joints, grasp_joints, lift_joints;
  // Where the path to the pregrasp starts: the current joints, or where the back-out ends.
  Eigen::VectorXd start_joints;
  // The IK solutions along the straight lines, each first at the line's start: the back-out from
  // the current joints (empty when the start is clear of the model), the approach, the lift.
  std::vector<Eigen::VectorXd> backout_path, approach_path, lift_path;
  double opening = 0;  // the pregrasp's, m
  double width = 0;    // the closed hand's: its pads on the contacts, m
  double spread = 0;   // m

  fba::JointTrajectory trajectory;  // from the current joints (the back-out first); every joint on every waypoint
  std::vector<fba::HandCommand> hand;  // in order, timed on the trajectory: the first once the back-out ends
  std::vector<ReachStep> steps;
  ReachFigures figures;
};

class ReachPlanner {
 public:
  // `urdf`: the arm; its chain from `base_link` (the world frame the grasp is in) to `flange_link`.
  // Throws arm::ArmModelError for the URDF, std::invalid_argument for parameters out of range.
  ReachPlanner(const std::filesystem::path& urdf, const ReachParams& params = {}, const std::string& base_link = "world",
               const std::string& flange_link = "flange");
  ReachPlanner(arm::ArmModel arm, const ReachParams& params = {});
  ~ReachPlanner();
  ReachPlanner(ReachPlanner&&) noexcept;
  ReachPlanner& operator=(ReachPlanner&&) noexcept;

  const arm::ArmModel& arm() const;
  const ReachParams& params() const;

  // The model's obstacles, built once for several grasps.
  static std::shared_ptr<const ModelObstacles> obstacles(const Octree& model);

  // Everything but the path search: the hand's placement, the current joints with the hand open
  // (backed out of the model when its hand is in it), the pregrasp's IK, the approach and the
  // lift. The plan it returns has the poses and joints, no trajectory.
  ReachPlan reachable(const Grasp& grasp, std::shared_ptr<const ModelObstacles> model, const Eigen::VectorXd& current) const;
  ReachPlan reachable(const Grasp& grasp, const Octree& model, const Eigen::VectorXd& current) const;
  // The whole plan.
  ReachPlan plan(const Grasp& grasp, std::shared_ptr<const ModelObstacles> model, const Eigen::VectorXd& current) const;
  ReachPlan plan(const Grasp& grasp, const Octree& model, const Eigen::VectorXd& current) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace fba::motion
