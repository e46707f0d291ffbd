// sim.hand: the simulated twin of a three-fingered hand (hw.robotiq_3f). Executes each fba.Grasp
// in the MuJoCo physics engine on the scene's object standing on a table: pregrasp, move in, close
// under force control, lift and hold (the lift test, lift_test.hpp), and reports what happened.
#include <cmath>
#include <string>

#include <nlohmann/json.hpp>

#include <fba/component.hpp>
#include <fba/types/grasp.hpp>
#include <fba/types/grasp_execution.hpp>

#include "fba/geometry/mesh_io.hpp"
#include "hand_ports.hpp"
#include "lift_test.hpp"

namespace {

constexpr double kDegree = M_PI / 180.0;

nlohmann::json to_json(const fba::GraspExecution& e) {
  nlohmann::json contacts = nlohmann::json::array();
  for (const auto& c : e.contacts)
    contacts.push_back({{"link", c.link},
                        {"position", {c.position.x(), c.position.y(), c.position.z()}},
                        {"normal", {c.normal.x(), c.normal.y(), c.normal.z()}},
                        {"force", c.force}});
  return {{"held", e.held},   {"slip_m", e.slip_m}, {"lift_height_m", e.lift_height_m},
          {"hold_s", e.hold_s}, {"reason", e.reason}, {"contacts", std::move(contacts)}};
}

class SimHand final : public fba::Component {
 public:
  static constexpr auto kGrasp = fba::hand::kGrasp;  // grasps in the frame the 'world' parameter names
  static constexpr auto kResult = fba::hand::kResult;
  static constexpr auto kHeld = fba::hand::kHeld;
  static constexpr auto kDropped = fba::hand::kDropped;
  // A reach plan's hand commands and the arm's trajectory, declared as hw.robotiq_3f does (the twins'
  // ports alike); not executed here yet: each command is logged.
  static constexpr auto kCommands = fba::hand::kCommands;
  static constexpr auto kTrajectory = fba::hand::kTrajectory;
  static constexpr fba::Param<std::filesystem::path> kMesh{
      "mesh", fba::required, "the object: any mesh assimp reads (OBJ, PLY, STL...), metres, z up; it rests on the table at z = 0"};
  static constexpr auto kObjectX = fba::Param<double>("object_x", 0.0, "the object's position on the table, metres").range(-1, 1);
  static constexpr auto kObjectY = fba::Param<double>("object_y", 0.0, "the object's position on the table, metres").range(-1, 1);
  static constexpr auto kObjectYaw = fba::Param<double>("object_yaw", 0.0, "the object's turn about z, degrees").range(-360, 360);
  static constexpr auto kObjectRest = fba::Param<std::string>(
      "object_rest", "upright", "how the object lies on the table: as the mesh stands, or on its side (turned 90 deg about the mesh's x)")
      .choices({"upright", "side"});
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
      fba::Param<double>("finger_force", 10.0, "force at each finger's pad when closing, newtons; the thumb pushes twice as hard").range(0.1, 100);

  static fba::Spec spec() {
    return fba::Spec::actuator("sim.hand",
                             "A three-fingered hand executing grasps in the MuJoCo physics engine: it lifts the object and "
                             "holds it, and reports the real contacts, whether it held and how far it slipped "
                             "(the twin of hw.robotiq_3f).")
        .add(kGrasp, kCommands, kTrajectory, kResult, kHeld, kDropped, kMesh, kObjectX, kObjectY, kObjectYaw, kObjectRest, kMass, kFriction, kLiftHeight, kHoldTime,
             kFingerForce, kWorld);
  }

  explicit SimHand(fba::Context& ctx) : ctx_(ctx), test_(make_test(ctx, table_shift_)) {
    if (ctx(kWorld) == "table") table_shift_ = 0;
    ctx.log().info("{}: {} triangles on the table at ({:.3f}, {:.3f}), yaw {:.1f} deg, {}", ctx(kMesh).stem().string(),
                   test_.object().triangles.size(), ctx(kObjectX), ctx(kObjectY), ctx(kObjectYaw), ctx(kObjectRest));
    if (!test_.physics_note().empty()) ctx.log().info("{}: {}", ctx(kMesh).stem().string(), test_.physics_note());
  }

  // Opens the hand and ends the simulation, as the real hand opens on its way out of a run.
  void safe_state() override { test_.stop(); }

  void process() override {
    if (auto in = ctx_(kCommands); in.has())
      ctx_.log().info("hand command ({} at {:.3f} s on the trajectory): not executed by sim.hand yet",
                      in.get().action == fba::HandCommand::Action::Close ? "close" : "open", in.get().time);
    if (!ctx_(kGrasp).has()) return;
    fba::Grasp grasp = ctx_(kGrasp).get();
    for (auto& c : grasp.contacts) c.position.z() += table_shift_;
    fba::GraspExecution result = test_.run(grasp);
    for (auto& c : result.contacts) c.position.z() -= table_shift_;
    result.stamp = static_cast<double>(ctx_.now_ns()) * 1e-9;
    ctx_.log().info("lift test: {} after {:.2f} simulated s ({} steps){}", result.held ? "held" : "failed", test_.simulated_s(),
                    test_.steps(), result.reason.empty() ? "" : ": " + result.reason);
    const std::string json = to_json(result).dump();
    ctx_.report("lift", json);  // the field's ground truth for "the grasp works"
    ctx_.emit(result.held ? kHeld : kDropped, json);
    ctx_(kResult).emit(std::move(result));
  }

 private:
  static fba::sim_hand::ObjectPlacement placement(fba::Context& ctx) {
    return {ctx(kObjectX), ctx(kObjectY), ctx(kObjectYaw) * kDegree, ctx(kObjectRest)};
  }
  // table_shift: how far the placed mesh is raised to rest on the table.
  static fba::sim_hand::LiftTest make_test(fba::Context& ctx, double& table_shift) {
    auto loaded = fba::geometry::load_mesh_with_warnings(ctx(kMesh));
    for (const auto& w : loaded.warnings) ctx.log().info("{}", w);
    fba::sim_hand::place_in_mesh_frame(loaded.mesh, placement(ctx), table_shift);
    fba::sim_hand::LiftTestParams p;
    p.mass = ctx(kMass);
    p.friction = ctx(kFriction);
    p.lift_height = ctx(kLiftHeight);
    p.hold_s = ctx(kHoldTime);
    p.finger_force = ctx(kFingerForce);
    return fba::sim_hand::LiftTest(loaded.mesh, placement(ctx), p);
  }

  fba::Context& ctx_;
  double table_shift_ = 0;  // z from the grasp's frame to the table's
  fba::sim_hand::LiftTest test_;
};

}  // namespace

FBA_COMPONENT(SimHand);
