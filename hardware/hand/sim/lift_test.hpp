// The lift test: the robot executes a grasp in the MuJoCo physics engine, the field's ground truth
// for "the grasp works". One world holds the whole robot as its one description has it
// (hardware/robots/wrist_camera_arm.urdf: the arm, the camera and the hand on its flange, generated
// into MJCF by robot_world.hpp), the table and the object, which collides as boxes (its
// voxelisation, geometry::decompose_into_boxes), not as its convex hull.
//
// The arm follows a timed joint trajectory (reach planning's, motion::ReachPlanner) with
// position-controlled joints: a computed-torque law (the mass matrix times a PD of the error, plus
// gravity and Coriolis) within the URDF's effort limits. The hand follows its commands at their
// times on the trajectory: open to an opening and spread, or close: each finger pushes with the
// force until it stops on the object, then keeps its place there (as the Robotiq's fingers stop
// at their current limit), so that it holds against a push as a stalled drive does. The
// verdict: any contact of the arm, the camera or the hand with the table or the object before the
// fingers close is a collision and the failure; after the close each finger must touch the object
// near its planned contact; "held" means the object rose with the hand and moved no more than the
// slip bound in the hand through the lift and the hold.
// Simulated time alone decides (the step count), never the wall clock.
#pragma once

#include <cstddef>
#include <filesystem>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "fba/types/grasp.hpp"
#include "fba/types/grasp_execution.hpp"
#include "fba/types/hand_command.hpp"
#include "fba/types/joint_trajectory.hpp"
#include "fba/types/mesh.hpp"
#include "object_placement.hpp"

namespace fba::sim_hand {

// A scene that cannot be built: a mesh that does not load, a robot description that does not
// parse, a model MuJoCo does not compile (with MuJoCo's own message).
class LiftTestError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct LiftTestParams {
  double mass = 0.3;          // kg, spread over the object's volume
  double friction = 0.5;      // sliding friction of the object, the table and the robot
  double lift_height = 0.1;   // metres, straight up (the reach plan's, when run() plans)
  double hold_s = 2.0;        // seconds held after the lift (idem)
  double finger_force = 15;   // newtons at each finger's pad, in the hand's 15-60; the thumb pushes twice as hard (idem)
  double clearance = 0.01;    // metres between each pad and its contact at the pregrasp (idem)
  // The object is out of the hand once it moved this far relative to the palm since closing: the
  // slip bound through the lift and the hold.
  double drop_distance = 0.03;
  // Each finger must touch the object within this distance of its planned contact, measured
  // across the approach (where along the finger it touches does not count); else the hand took
  // another grasp than the one planned, and the test fails without lifting.
  double contact_tolerance = 0.025;
  // The edge of the object's voxels, whose boxes MuJoCo collides: the boxes' surface lies within
  // half a voxel's diagonal of the mesh's.
  double voxel_size = 0.003;
  // Where run()'s plans start: the arm's joints (empty: the hand pointing down over the
  // workspace's centre, its fingertips 25 cm over the table).
  std::vector<double> start_joints;
};

// The robot: its description and where its parts were measured to be.
struct RobotSetup {
  std::string urdf;          // URDF text; empty: the project's (built in)
  std::string urdf_name;     // names it in messages
  // Fixed joints' origins in place of the URDF's (arm::with_fixed_joint_origins): the measured
  // world_to_base, flange_to_palm, flange_to_camera. (sim.hand gives `urdf` with them in place
  // already: arm::RobotParameters::read.)
  std::map<std::string, Eigen::Isometry3d> origins;
};

// What MuJoCo was given for the object: a convex mesh (its volume at least kConvexVolumeShare of
// its hull's) as its hull, one exact piece; any other as boxes of voxels (box_decomposition.hpp).
struct ObjectPieces {
  bool hull = false;       // the object collides as its convex hull, not as the boxes
  double hull_volume = 0;  // m^3, of the mesh's convex hull
  std::size_t boxes = 0;   // the voxels' boxes (the lift test's own reach planning uses them either way)
  double voxel_size = 0;   // m
  double iou = 0;          // volume IoU of the boxes against the mesh
  double volume = 0;       // m^3, of the boxes
  double mesh_volume = 0;  // m^3
};

// What MuJoCo collides the object as, in words: "MuJoCo collides it as its convex hull: ...", or
// as how many boxes of which voxels, their fit and why not the hull.
std::string describe(const ObjectPieces& pieces);

// `mesh` is in the mesh file's frame; see ObjectPlacement. Throws LiftTestError, and
// std::invalid_argument for parameters out of range.
class LiftTest {
 public:
  LiftTest(const TriangleMesh& mesh, const ObjectPlacement& placement, const LiftTestParams& params = {},
           const RobotSetup& robot = {});
  ~LiftTest();
  LiftTest(const LiftTest&) = delete;
  LiftTest& operator=(const LiftTest&) = delete;

  // Plans the reach for the grasp (motion::ReachPlanner, from the start joints, the object's boxes
  // as the model) and executes the plan. The pregrasp opens wider, a centimetre a side at a time,
  // while the way in meets the object. A grasp the arm cannot take gives held = false with the
  // planner's refusal as the reason. Throws std::invalid_argument for a grasp with non-finite
  // values or a zero approach.
  GraspExecution run(const Grasp& grasp);

  // Executes a reach plan: the arm starts at the trajectory's first waypoint (the object settled
  // on the table), follows it, and the hand takes its commands at their times. `planned`, when
  // given, is the grasp the plan is for: each finger's contact is checked against it. The
  // simulation ends at the end of the hold (the motion after the lift, the first still stretch),
  // or at the trajectory's end. Throws std::invalid_argument for a trajectory whose joints are not
  // the arm's, or whose times do not increase.
  GraspExecution execute(const JointTrajectory& trajectory, const std::vector<HandCommand>& commands,
                         const Grasp* planned = nullptr);

  // The safe state, from any thread: a run in progress opens the hand and ends (held = false, the
  // reason says so), and later runs end at once the same way.
  void stop();

  // The object as placed, world frame: for computing contacts on it.
  const TriangleMesh& object() const;
  const ObjectPieces& pieces() const;
  // Simulated seconds and physics steps of the last run.
  double simulated_s() const;
  long steps() const;
  // The reach plan's figures of the last run(): "" before one; else e.g. "7.84 s of motion, path
  // 1.90 rad, straight".
  const std::string& plan_note() const;

  // The world MuJoCo was given (MJCF text).
  const std::string& world_mjcf() const;
  // The arm's joints, in the trajectory's order.
  const std::vector<std::string>& arm_joints() const;
  // The joints run() starts from.
  Eigen::VectorXd start_joints() const;
  // The world pose of a body (a URDF link's name) with the arm at `joints` and the hand open: for
  // comparing the world with the kinematics.
  Eigen::Isometry3d body_pose(const std::string& link, const Eigen::VectorXd& joints);

  // The project's robot, built in: hardware/robots/wrist_camera_arm.urdf's text.
  static const std::string& robot_urdf();

 private:
  struct Impl;
  GraspExecution run_steps(const JointTrajectory& trajectory, const std::vector<HandCommand>& commands, const Grasp* planned);
  std::unique_ptr<Impl> impl_;
};

}  // namespace fba::sim_hand
