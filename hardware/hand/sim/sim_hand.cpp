// sim.hand: the simulated twin of a three-fingered hand (hw.robotiq_3f). Executes each fba.Grasp
// in the MuJoCo physics engine with the whole robot, the table and the scene's object: the arm
// carries the hand to the grasp on reach planning's trajectory, the fingers close under force
// control, the arm lifts and holds (the lift test, lift_test.hpp); it reports what happened.
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <fba/component.hpp>
#include <fba/types/grasp.hpp>
#include <fba/types/grasp_execution.hpp>
#include <fba/types/grasp_execution_json.hpp>
#include <fba/types/hand_command.hpp>
#include <fba/types/joint_trajectory.hpp>

#include "../robotiq_3f/grip_force.hpp"
#include "fba/geometry/mesh_io.hpp"
#include "hand_ports.hpp"
#include "lift_test.hpp"
#include "object_placement_params.hpp"
#include "robot_parameters.hpp"

namespace {

// The result as every hand reports it, with what only a simulation measures.
nlohmann::json to_json(const fba::GraspExecution& e) {
  nlohmann::json out = fba::grasp_execution_json(e);
  out["slip_m"] = e.slip_m;
  out["lift_height_m"] = e.lift_height_m;
  return out;
}

nlohmann::json to_json(const fba::sim_hand::ObjectPieces& p) {
  return {{"collides_as", p.hull ? "convex hull" : "boxes"}, {"hull_volume_m3", p.hull_volume}, {"boxes", p.boxes}, {"voxel_m", p.voxel_size},
          {"iou", p.iou}, {"volume_m3", p.volume}, {"mesh_volume_m3", p.mesh_volume}};
}


class SimHand final : public fba::Component {
 public:
  static constexpr auto kGrasp = fba::hand::kGrasp;  // grasps in the frame the 'world' parameter names
  static constexpr auto kResult = fba::hand::kResult;
  static constexpr auto kHeld = fba::hand::kHeld;
  static constexpr auto kDropped = fba::hand::kDropped;
  // A reach plan's hand commands and the arm's trajectory, as hw.robotiq_3f takes them: the arm in
  // the world follows the trajectory, the hand the commands at their times on it.
  static constexpr auto kCommands = fba::hand::kCommands;
  static constexpr auto kTrajectory = fba::hand::kTrajectory;
  // The object and its placement, the same parameters as sim.camera's (object_placement_params.hpp).
  static constexpr auto kMesh = fba::sim_hand::kObjectMesh;
  static constexpr auto kObjectX = fba::sim_hand::kObjectX;
  static constexpr auto kObjectY = fba::sim_hand::kObjectY;
  static constexpr auto kObjectYaw = fba::sim_hand::kObjectYaw;
  static constexpr auto kObjectRest = fba::sim_hand::kObjectRest;
  static constexpr auto kMass = fba::Param<double>("mass", 0.3, "the object's mass, kg").range(0.001, 10);
  static constexpr auto kFriction = fba::Param<double>("friction", 0.5, "sliding friction of object, table and fingers").range(0.01, 2);
  static constexpr auto kLiftHeight = fba::Param<double>("lift_height", 0.1, "how far the hand lifts the object, metres").range(0.001, 1);
  static constexpr auto kHoldTime = fba::Param<double>("hold_time", 2.0, "simulated seconds the object is held after lifting").range(0, 60);
  static constexpr auto kWorld =
      fba::Param<std::string>("world", "table",
                              "the frame of grasps and reported contacts: 'table', where the object rests on z = 0, or 'mesh', "
                              "the mesh file's own coordinates (turned and moved by object_rest, object_yaw, object_x, object_y, not "
                              "raised); sim.camera has the same parameters, so that both see the same object")
          .choices({"table", "mesh"});
  static constexpr auto kFingerForce =
      fba::Param<double>("finger_force", fba::robotiq::kMinForce,
                         "force at each finger's pad when closing, newtons, where a close names none (a grasp executed alone); the thumb "
                         "pushes twice as hard. The Robotiq's range: a close asking for more or less closes with its nearest, as "
                         "hw.robotiq_3f does")
          .range(fba::robotiq::kMinForce, fba::robotiq::kMaxForce);
  // The robot (urdf, base_pose, flange_to_palm, flange_to_camera), as every component that reads
  // it takes it: the world's arm, camera and hand.
  using Robot = fba::arm::RobotParameters;
  static constexpr auto kVoxelSize = fba::Param<double>(
      "voxel_size", 0.003, "the edge of the voxels whose boxes the object collides as in MuJoCo, metres").range(0.0005, 0.02);
  static inline const auto kStartJoints = fba::Param<std::vector<double>>(
      "start_joints", std::vector<double>{},
      "the arm's joints where each grasp's reach plan starts, in the URDF's order; empty: sim.arm's initial pose drawn back 20 cm");

  static fba::Spec spec() {
    fba::Spec spec = fba::Spec::actuator("sim.hand",
                                         "A three-fingered hand executing grasps in the MuJoCo physics engine: it lifts the object and "
                                         "holds it, and reports the real contacts, whether it held and how far it slipped "
                                         "(the twin of hw.robotiq_3f).");
    spec.add(kGrasp, kCommands, kTrajectory, kResult, kHeld, kDropped, kMesh, kObjectX, kObjectY, kObjectYaw, kObjectRest, kMass, kFriction,
             kLiftHeight, kHoldTime, kFingerForce, kWorld);
    Robot::add(spec).add(kVoxelSize, kStartJoints);
    return spec;
  }

  explicit SimHand(fba::Context& ctx) : ctx_(ctx), test_(make_test(ctx, table_shift_)) {
    if (ctx(kWorld) == "table") table_shift_ = 0;
    ctx.log().info("{}: {} triangles on the table at ({:.3f}, {:.3f}), yaw {:.1f} deg, {}", ctx(kMesh).stem().string(),
                   test_.object().triangles.size(), ctx(kObjectX), ctx(kObjectY), ctx(kObjectYaw), ctx(kObjectRest));
    ctx.log().info("{}: {}", ctx(kMesh).stem().string(), fba::sim_hand::describe(test_.pieces()));
  }

  // Opens the hand and ends the simulation, as the real hand opens on its way out of a run.
  void safe_state() override { test_.stop(); }

  // Without commands connected, each grasp is executed on the world's own reach plan (the lift
  // test). With them, a grasp names the planned contacts, a trajectory starts a new plan, and the
  // plan runs in the world at its close (once its trajectory is in, when one is connected): the
  // commands' times count from the trajectory's start, as the arm's motion does.
  void process() override {
    if (auto in = ctx_(kGrasp); in.has()) {
      fba::Grasp grasp = in.get();
      for (auto& c : grasp.contacts) c.position.z() += table_shift_;
      if (!ctx_(kCommands).connected()) return finish(test_.run(grasp));
      planned_ = grasp;
    }
    if (auto in = ctx_(kTrajectory); in.has()) {  // a new plan: its commands follow
      trajectory_ = in.get();
      commands_.clear();
    }
    if (auto in = ctx_(kCommands); in.has()) {
      const bool timed = ctx_(kTrajectory).connected();
      if (!timed && done_) commands_.clear();  // without trajectories, a close ends a plan
      done_ = false;
      commands_.push_back(in.get());
      if (in.get().action != fba::HandCommand::Action::Close) return;
      if (const double f = in.get().force; f > 0 && fba::robotiq::grip_force(f) != f)
        ctx_.log().warn("a close with {} N: the hand pushes with {} to {} N, so with {} N", f, fba::robotiq::kMinForce,
                        fba::robotiq::kMaxForce, fba::robotiq::grip_force(f));
      done_ = true;
      if (timed && !trajectory_) {
        fba::GraspExecution refused;
        refused.reason = "a close before any trajectory: its time counts from the trajectory's arrival";
        return finish(std::move(refused));
      }
    } else {
      return;
    }
    const fba::Grasp* planned = planned_ ? &*planned_ : nullptr;
    try {
      if (trajectory_) return finish(test_.execute(*trajectory_, commands_, planned));
      // No trajectory to follow: the arm stands where it starts while the hand opens and closes,
      // the close a second after the open.
      fba::JointTrajectory still;
      still.names = test_.arm_joints();
      const Eigen::VectorXd q = test_.start_joints();
      std::vector<fba::HandCommand> timed = commands_;
      for (auto& c : timed) c.time = c.action == fba::HandCommand::Action::Close ? 1.0 : 0.0;
      for (double t : {0.0, 3.0}) still.points.push_back({t, {q.data(), q.data() + q.size()}, std::vector<double>(q.size(), 0.0)});
      finish(test_.execute(still, timed, planned));
    } catch (const std::invalid_argument& e) {  // a trajectory this arm cannot follow: the arm refuses it too
      fba::GraspExecution refused;
      refused.reason = std::string("the trajectory cannot be followed: ") + e.what();
      finish(std::move(refused));
    }
  }

 private:
  void finish(fba::GraspExecution result) {
    for (auto& c : result.contacts) c.position.z() -= table_shift_;
    result.stamp = static_cast<double>(ctx_.now_ns()) * 1e-9;
    ctx_.log().info("lift test: {} after {:.2f} simulated s ({} steps){}{}", result.held ? "held" : "failed", test_.simulated_s(),
                    test_.steps(), test_.plan_note().empty() ? "" : ", reach plan: " + test_.plan_note(),
                    result.reason.empty() ? "" : ": " + result.reason);
    nlohmann::json report = to_json(result);
    report["object"] = to_json(test_.pieces());
    const std::string json = report.dump();
    ctx_.report("lift", json);  // the field's ground truth for "the grasp works"
    ctx_.emit(result.held ? kHeld : kDropped, json);
    ctx_(kResult).emit(std::move(result));
  }

  // table_shift: how far the placed mesh is raised to rest on the table.
  static fba::sim_hand::LiftTest make_test(fba::Context& ctx, double& table_shift) {
    auto loaded = fba::geometry::load_mesh_with_warnings(ctx(kMesh));
    for (const auto& w : loaded.warnings) ctx.log().info("{}", w);
    fba::sim_hand::place_in_mesh_frame(loaded.mesh, fba::sim_hand::object_placement(ctx), table_shift);
    fba::sim_hand::LiftTestParams p;
    p.mass = ctx(kMass);
    p.friction = ctx(kFriction);
    p.lift_height = ctx(kLiftHeight);
    p.hold_s = ctx(kHoldTime);
    p.finger_force = ctx(kFingerForce);
    p.voxel_size = ctx(kVoxelSize);
    p.start_joints = ctx(kStartJoints);
    // The robot's URDF with the measured origins already in place.
    const fba::arm::RobotDescription described = Robot::read(ctx);
    fba::sim_hand::RobotSetup robot;
    robot.urdf = described.urdf;
    robot.urdf_name = described.name;
    return fba::sim_hand::LiftTest(loaded.mesh, fba::sim_hand::object_placement(ctx), p, robot);
  }

  fba::Context& ctx_;
  double table_shift_ = 0;  // z from the grasp's frame to the table's
  fba::sim_hand::LiftTest test_;
  // The plan being received: the grasp it is for, its trajectory, its commands so far, and whether
  // it ran (at its close).
  std::optional<fba::Grasp> planned_;
  std::optional<fba::JointTrajectory> trajectory_;
  std::vector<fba::HandCommand> commands_;
  bool done_ = false;
};

}  // namespace

FBA_COMPONENT(SimHand);
