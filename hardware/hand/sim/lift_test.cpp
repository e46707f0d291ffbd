#include "lift_test.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <functional>
#include <map>
#include <mutex>

#include <fmt/format.h>
#include <mujoco/mujoco.h>

#include "../robotiq_3f/grip_force.hpp"
#include "arm_model.hpp"
#include "fba/geometry/box_decomposition.hpp"
#include "fba/geometry/convex_hull.hpp"
#include "fba/geometry/decimate.hpp"
#include "fba/motion/reach_planner.hpp"
#include "robot_urdf.hpp"
#include "robot_world.hpp"
#include "trajectory_reference.hpp"
#include "voxel_octree.hpp"

namespace fba::sim_hand {

namespace {

// MuJoCo's default error handler ends the process; a scene that overflows its memory must be a
// failed test, not a dead task. libmujoco is built with unwind tables (amd64), so an exception
// passes through it.
[[noreturn]] void throw_mujoco_error(const char* message) { throw LiftTestError(std::string("MuJoCo: ") + message); }
// Warnings (an unstable simulation) are read from mjData after each step instead of printed.
void ignore_mujoco_warning(const char*) {}

void install_mujoco_handlers() {
  static std::once_flag once;
  std::call_once(once, [] {
    mju_user_error = throw_mujoco_error;
    mju_user_warning = ignore_mujoco_warning;
  });
}

struct VfsDeleter {
  void operator()(mjVFS* v) const {
    mj_deleteVFS(v);
    delete v;
  }
};

void add_file(mjVFS& vfs, const std::string& name, const std::string& data) {
  if (mj_makeEmptyFileVFS(&vfs, name.c_str(), static_cast<int>(data.size())) != 0)
    throw LiftTestError("lift test: cannot add " + name + " to MuJoCo's virtual file system");
  const int i = mj_findFileVFS(&vfs, name.c_str());
  std::memcpy(vfs.filedata[i], data.data(), data.size());
}

// The arm's joints follow the trajectory under a computed-torque law: the acceleration the
// trajectory asks plus a critically damped PD of the error, times the mass matrix, plus gravity and
// Coriolis; a 10 Hz bandwidth, the torques within the URDF's effort limits (as a real arm's
// controller compensates its own weight and limits its motors' current).
constexpr double kArmBandwidth = 2 * M_PI * 10;  // rad/s
constexpr double kArmKp = kArmBandwidth * kArmBandwidth;
constexpr double kArmKd = 2 * kArmBandwidth;
// The closing slides hold the commanded opening with a proportional law (N/m; the joints' damping
// damps it), within the finger force.
constexpr double kHoldGain = 2000;
// A closing finger stops where it meets the object, as the Robotiq's do (its manual, section 4: the
// force request limits the motor's current, and a finger that reaches it stops and reports an
// object): its slide has stopped once it moves slower than kStoppedSpeed (m/s), from kStartup (s)
// after the close on (a finger that meets nothing closes at 0.2 m/s by then). From then it keeps
// its place as a stalled drive does, pressing with the force it stopped at and stiffly
// (kStopStiffness, N/m) against a push, up to the hand's largest grip force (robotiq::kMaxForce at
// a finger's pad; the thumb's twice). So an object's weight along the squeeze is met by the stopped
// fingers, not by their drives' force alone, which would let the object and the fingers slide
// together across the hand.
constexpr double kStartup = 0.05;
constexpr double kStoppedSpeed = 0.002;
constexpr double kStopStiffness = 20000;
// The object settles on the table before the trajectory starts; the way in is then checked
// against it where it rests.
constexpr double kSettle_s = 0.2;

// sim.arm's initial joints (the camera 0.35 m from the workspace's centre, 60 degrees up): the
// seed of the start pose's IK.
const std::vector<double> kArmHome{-0.4148, -2.1223, 2.2888, -2.2234, -1.3679, -0.3644};
// run()'s plans start with the hand pointing down over the workspace's centre, its fingertips
// this high over the table (above the tallest object the workspace holds), so that a grasp from
// above needs a short path. The fingers reach about this far past the palm's frame.
constexpr double kStartClearance = 0.25;
constexpr double kFingerReach = 0.18;
// At most this many vertices of a convex object's hull go to MuJoCo, and the hull is taken of at
// most this many of the mesh's triangles (see the constructor).
constexpr std::size_t kMaxHullVertices = 1000;
constexpr std::size_t kHullTriangles = 50000;

std::string seconds(double t) { return fmt::format("t={:.2f} s", t); }

}  // namespace

const std::string& LiftTest::robot_urdf() {
  static const std::string text(kRobotUrdf);
  return text;
}

struct LiftTest::Impl {
  LiftTestParams params;
  TriangleMesh object;
  ObjectPieces pieces;
  std::string mjcf;
  std::string plan_note;
  // run()'s planners, by the pregrasp's clearance in mm: the robot's URDF with the measured
  // transforms in place, and the reach parameters but the clearance.
  std::string urdf, urdf_name;
  motion::ReachParams reach;
  std::map<long, std::unique_ptr<motion::ReachPlanner>> planners;
  std::shared_ptr<const motion::ModelObstacles> obstacles;
  Eigen::VectorXd start;
  mjModel* m = nullptr;
  mjData* d = nullptr;

  // Indices in the model, looked up once by name.
  int palm_body = -1, object_body = -1, table_geom = -1, robot_root = -1;
  std::vector<std::string> arm_names;
  std::vector<int> arm_qpos, arm_dof, arm_actuator;
  std::vector<double> arm_effort;
  struct Finger {
    std::string name;
    int close_joint = -1, close_actuator = -1;  // the closing slide, force driven
    double gear = 1;                            // its force over a finger's: the thumb pushes for two
    std::vector<int> phalanx_actuators;         // the phalanges' springs
    int spread_joint = -1, spread_actuator = -1;  // -1 for the thumb
  };
  std::array<Finger, 3> fingers;  // thumb, finger_a (+y), finger_b (-y)
  // The hand's geometry, read from the model: the fully open knuckles' distance from the palm's
  // centre along x, the pad's radius, the closing slides' travel, the scissor's range.
  double knuckle_x = 0, pad_radius = 0, travel = 0, spread_min = 0, spread_max = 0, spread_force = 0;
  long steps = 0;
  std::atomic<bool> stop{false};
  struct Stopped {};  // thrown out of a step once stop is set
  struct Run;

  ~Impl() {
    if (d) mj_deleteData(d);
    if (m) mj_deleteModel(m);
  }

  // Compiles mjcf into MuJoCo's model and data and looks up the indices run() drives by name.
  void compile(const std::vector<std::string>& arm_joints) {
    std::unique_ptr<mjVFS, VfsDeleter> vfs(new mjVFS);
    mj_defaultVFS(vfs.get());
    add_file(*vfs, "world.xml", mjcf);
    char error[1024] = "";
    m = mj_loadXML("world.xml", vfs.get(), error, sizeof error);
    if (!m) throw LiftTestError(std::string("lift test: MuJoCo does not compile the robot's world: ") + error);
    d = mj_makeData(m);
    if (!d) throw LiftTestError("lift test: MuJoCo could not allocate the simulation data");

    palm_body = id(mjOBJ_BODY, "palm");
    object_body = id(mjOBJ_BODY, "object");
    table_geom = id(mjOBJ_GEOM, "table");
    robot_root = m->body_rootid[palm_body];
    for (const std::string& joint : arm_joints) {
      const int j = id(mjOBJ_JOINT, joint);
      const int a = id(mjOBJ_ACTUATOR, joint);
      arm_names.push_back(joint);
      arm_qpos.push_back(m->jnt_qposadr[j]);
      arm_dof.push_back(m->jnt_dofadr[j]);
      arm_actuator.push_back(a);
      arm_effort.push_back(m->actuator_ctrlrange[2 * a + 1]);
    }
    const char* names[3] = {"thumb", "finger_a", "finger_b"};
    for (int f = 0; f < 3; ++f) {
      auto& finger = fingers[static_cast<std::size_t>(f)];
      finger.name = names[f];
      finger.close_joint = id(mjOBJ_JOINT, finger.name + "_close");
      finger.close_actuator = id(mjOBJ_ACTUATOR, finger.name + "_close");
      finger.gear = f == 0 ? 2 : 1;
      for (const char* k : {"_1", "_2", "_3"}) finger.phalanx_actuators.push_back(id(mjOBJ_ACTUATOR, finger.name + k));
      if (f > 0) {
        finger.spread_joint = id(mjOBJ_JOINT, finger.name + "_spread");
        finger.spread_actuator = id(mjOBJ_ACTUATOR, finger.name + "_spread");
      }
    }
    knuckle_x = -m->body_pos[3 * id(mjOBJ_BODY, "thumb_carriage")];
    pad_radius = m->geom_size[3 * id(mjOBJ_GEOM, "thumb_3")];
    travel = m->jnt_range[2 * fingers[0].close_joint + 1];
    const int spread = fingers[1].spread_joint;
    spread_min = 2 * m->jnt_range[2 * spread];
    spread_max = 2 * m->jnt_range[2 * spread + 1];
    spread_force = m->actuator_forcerange[2 * fingers[1].spread_actuator + 1];
  }

  const motion::ReachPlanner& planner(double clearance) {
    auto& p = planners[std::lround(clearance * 1000)];
    if (!p) {
      motion::ReachParams r = reach;
      r.clearance = clearance;
      p = std::make_unique<motion::ReachPlanner>(arm::ArmModel::from_string(urdf, urdf_name, "world", "flange"), r);
    }
    return *p;
  }

  int id(mjtObj type, const std::string& name) const {
    const int i = mj_name2id(m, type, name.c_str());
    if (i < 0) throw LiftTestError("lift test: the robot's world has no " + std::string(mju_type2Str(type)) + " named '" + name + "'");
    return i;
  }

  std::string geom_name(int g) const {
    const char* n = mj_id2name(m, mjOBJ_GEOM, g);
    return n ? n : "geom " + std::to_string(g);
  }
  // The object's boxes are named object_N: one name for all in messages.
  std::string part_name(int g) const { return is_object(g) ? "the object" : g == table_geom ? "the table" : geom_name(g); }

  bool is_robot(int geom) const { return m->body_rootid[m->geom_bodyid[geom]] == robot_root; }
  bool is_object(int geom) const { return m->geom_bodyid[geom] == object_body; }

  // The first contact of the robot with the table or the object, as "<part> touches <other> at (x, y, z)" (world, m).
  std::string robot_collision() const {
    for (int i = 0; i < d->ncon; ++i) {
      const mjContact& c = d->contact[i];
      if (c.dist > 0) continue;  // within the margin, not touching
      for (auto [r, o] : {std::pair{c.geom1, c.geom2}, std::pair{c.geom2, c.geom1}})
        if (is_robot(r) && !is_robot(o))
          return fmt::format("{} touches {} at ({:.3f}, {:.3f}, {:.3f})", geom_name(r), part_name(o), c.pos[0], c.pos[1], c.pos[2]);
    }
    return {};
  }

  std::vector<ExecutedContact> object_contacts() const {
    std::vector<ExecutedContact> out;
    for (int i = 0; i < d->ncon; ++i) {
      const mjContact& c = d->contact[i];
      const bool object_second = is_robot(c.geom1) && is_object(c.geom2);
      if (!object_second && !(is_robot(c.geom2) && is_object(c.geom1))) continue;
      mjtNum f[6];
      mj_contactForce(m, d, i, f);
      if (f[0] <= 0) continue;
      ExecutedContact e;
      e.link = geom_name(object_second ? c.geom1 : c.geom2);
      e.position = Eigen::Vector3d(c.pos[0], c.pos[1], c.pos[2]);
      // The contact frame's normal points from geom1 to geom2.
      e.normal = Eigen::Vector3d(c.frame[0], c.frame[1], c.frame[2]) * (object_second ? 1.0 : -1.0);
      e.force = f[0];
      // Two of the object's boxes that overlap under a finger give the same contact twice, the
      // force shared between them: one contact, with their force.
      auto same = [&](const ExecutedContact& o) { return o.link == e.link && (o.position - e.position).norm() < 1e-9; };
      if (auto it = std::find_if(out.begin(), out.end(), same); it != out.end()) {
        it->force += e.force;
        continue;
      }
      out.push_back(std::move(e));
    }
    return out;
  }

  Eigen::Vector3d object_centre() const {
    const mjtNum* p = d->xipos + 3 * object_body;
    return {p[0], p[1], p[2]};
  }
  Eigen::Isometry3d body_pose(int body) const {
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    const Eigen::Map<const Eigen::Matrix<mjtNum, 3, 3, Eigen::RowMajor>> r(d->xmat + 9 * body);
    t.linear() = r;
    t.translation() << d->xpos[3 * body], d->xpos[3 * body + 1], d->xpos[3 * body + 2];
    return t;
  }
  Eigen::Vector3d in_palm(const Eigen::Vector3d& world) const { return body_pose(palm_body).inverse() * world; }

  bool unstable() const { return d->warning[mjWARN_BADQACC].number > 0; }

  // The slide travel at which a pad's inner surface is half_opening from the palm's centre.
  double travel_for(double half_opening) const { return std::clamp(knuckle_x - pad_radius - half_opening, 0.0, travel); }

  // The fingers' spread an open command sets: its mode's, or in basic mode its own.
  double spread_for(const HandCommand& c) const {
    switch (c.mode) {
      case HandCommand::Mode::Pinch: return spread_min;
      case HandCommand::Mode::Wide:
      case HandCommand::Mode::Scissor: return spread_max;
      case HandCommand::Mode::Basic: break;
    }
    return c.spread;
  }

  // The trajectory's columns of the arm's joints, in the arm's order. Throws std::invalid_argument
  // for a trajectory without waypoints or without one of the arm's joints, with waypoints of
  // another size, or with times that do not increase.
  std::vector<int> arm_columns(const JointTrajectory& trajectory) const {
    if (trajectory.points.empty()) throw std::invalid_argument("lift test: the trajectory has no waypoint");
    std::vector<int> column;
    for (const std::string& joint : arm_names) {
      const auto it = std::find(trajectory.names.begin(), trajectory.names.end(), joint);
      if (it == trajectory.names.end())
        throw std::invalid_argument("lift test: the trajectory has no joint '" + joint + "' of the arm's");
      column.push_back(static_cast<int>(it - trajectory.names.begin()));
    }
    for (std::size_t i = 0; i < trajectory.points.size(); ++i) {
      const auto& pt = trajectory.points[i];
      if (pt.positions.size() != trajectory.names.size() || (!pt.velocities.empty() && pt.velocities.size() != trajectory.names.size()))
        throw std::invalid_argument("lift test: waypoint " + std::to_string(i) + " has " + std::to_string(pt.positions.size()) +
                                    " positions and " + std::to_string(pt.velocities.size()) + " velocities for " +
                                    std::to_string(trajectory.names.size()) + " joints");
      if (i > 0 && !(pt.time > trajectory.points[i - 1].time))
        throw std::invalid_argument("lift test: the trajectory's times must increase; waypoint " + std::to_string(i) + " is at " +
                                    std::to_string(pt.time) + " s after " + std::to_string(trajectory.points[i - 1].time) + " s");
    }
    return column;
  }

  // The arm at q, still; the hand open by `open_travel` with the fingers `spread` apart. No time passes.
  void pose(const Eigen::VectorXd& q, double open_travel, double spread) {
    for (std::size_t i = 0; i < arm_qpos.size(); ++i) d->qpos[arm_qpos[i]] = q(static_cast<Eigen::Index>(i));
    const double half = std::clamp(spread, spread_min, spread_max) / 2;
    for (std::size_t f = 0; f < 3; ++f) {
      const auto& finger = fingers[f];
      d->qpos[m->jnt_qposadr[finger.close_joint]] = open_travel;
      for (int act : finger.phalanx_actuators) d->ctrl[act] = 0;
      if (finger.spread_joint >= 0) {
        const double offset = f == 1 ? half : -half;
        d->qpos[m->jnt_qposadr[finger.spread_joint]] = offset;
        d->ctrl[finger.spread_actuator] = offset;
      }
    }
    mj_forward(m, d);
  }
};

LiftTest::LiftTest(const TriangleMesh& mesh, const ObjectPlacement& placement, const LiftTestParams& params, const RobotSetup& robot)
    : impl_(std::make_unique<Impl>()) {
  install_mujoco_handlers();
  if (mesh.triangles.empty()) throw LiftTestError("lift test: the object mesh has no triangles");
  if (!(params.mass > 0) || !(params.friction > 0) || !(params.lift_height > 0) || !(params.hold_s >= 0) ||
      !(params.drop_distance > 0) || !(params.clearance >= 0) || !(params.contact_tolerance > 0) || !(params.voxel_size > 0))
    throw std::invalid_argument("lift test: mass, friction, lift height, drop distance, contact tolerance and voxel size "
                                "must be positive, hold time and clearance not negative");
  if (!(params.finger_force >= robotiq::kMinForce && params.finger_force <= robotiq::kMaxForce))
    throw std::invalid_argument(fmt::format("lift test: the finger force must be within the hand's {} to {} N; found {} N",
                                            robotiq::kMinForce, robotiq::kMaxForce, params.finger_force));
  auto& s = *impl_;
  s.params = params;
  s.object = place_on_table(mesh, placement);

  // The object as boxes: its voxelisation merged, whose fit is known; a convex object as its hull,
  // exact and smooth where the boxes would be a staircase of ledges a fingertip rests on.
  geometry::BoxDecomposition pieces;
  geometry::ConvexHull hull;
  try {
    pieces = geometry::decompose_into_boxes(s.object, params.voxel_size);
    // Convexity is judged on the mesh's hull (clustered only beyond kHullTriangles, whose cells
    // are then about a millimetre: qhull merges a fine mesh's flat faces for minutes), not on a
    // coarse one, whose clusters cut a scan's rims and corners.
    hull = geometry::convex_hull(geometry::decimate(s.object, kHullTriangles).mesh);
  } catch (const std::exception& e) {  // std::invalid_argument, geometry::ConvexHullError
    throw LiftTestError(std::string("lift test: the object cannot be given to MuJoCo: ") + e.what());
  }
  const bool convex = pieces.mesh_volume >= geometry::kConvexVolumeShare * hull.volume;
  // MuJoCo walks a hull's vertices in every collision test near it: a fine convex mesh touches the
  // robot as the hull of the mesh clustered to a few thousand triangles (moved inwards by a
  // cluster's sagitta: under a tenth of a millimetre on a 10 cm sphere).
  if (convex && hull.vertices.size() > kMaxHullVertices)
    hull.vertices = geometry::convex_hull(geometry::decimate(s.object, 2 * kMaxHullVertices).mesh).vertices;
  s.pieces = {convex, hull.volume, pieces.boxes.size(), pieces.voxel_size, pieces.iou, pieces.volume, pieces.mesh_volume};

  // The robot: its one description, with the measured transforms in place.
  const std::string name = robot.urdf.empty() ? "wrist_camera_arm.urdf (built in)" : robot.urdf_name.empty() ? "the robot's URDF" : robot.urdf_name;
  std::string urdf;
  try {
    urdf = arm::with_fixed_joint_origins(robot.urdf.empty() ? robot_urdf() : robot.urdf, robot.origins, name);
    const arm::ArmModel to_flange = arm::ArmModel::from_string(urdf, name, "world", "flange");
    const arm::ArmModel to_palm = arm::ArmModel::from_string(urdf, name, "world", "palm");
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(to_flange.size()));
    motion::ReachParams& reach = s.reach;
    reach.flange_from_palm = to_flange.forward(zero).inverse() * to_palm.forward(zero);
    reach.clearance = params.clearance;
    reach.lift_height = params.lift_height;
    reach.hold_s = params.hold_s;
    reach.finger_force = params.finger_force;
    reach.retreat = false;  // the verdict is in at the hold's end
    // The model is the object itself, not a visual hull larger than it: no allowance around the
    // contacts, where the fingers would touch the model before they touch the object.
    reach.contact_allowance = 0;
    if (params.start_joints.empty()) {
      // The hand pointing down over the workspace, its fingertips kStartClearance above the table.
      const Eigen::VectorXd home = Eigen::Map<const Eigen::VectorXd>(kArmHome.data(), static_cast<Eigen::Index>(kArmHome.size()));
      const Eigen::Isometry3d palm_on_flange = to_flange.forward(zero).inverse() * to_palm.forward(zero);
      Eigen::Isometry3d palm = Eigen::Isometry3d::Identity();
      palm.linear() << 1, 0, 0, 0, -1, 0, 0, 0, -1;  // z down, x along the world's x
      palm.translation() << 0, 0, kStartClearance + kFingerReach;
      const auto ready = to_flange.inverse(palm * palm_on_flange.inverse(), home);
      if (!ready.ok) throw LiftTestError("lift test: no start joints: the hand over the workspace is out of the arm's reach: " + ready.why);
      s.start = ready.joints;
    } else {
      s.start = Eigen::Map<const Eigen::VectorXd>(params.start_joints.data(), static_cast<Eigen::Index>(params.start_joints.size()));
      if (const std::string bad = to_flange.limit_violation(s.start); !bad.empty())
        throw std::invalid_argument("lift test: the start joints are not usable: " + bad);
    }
    s.urdf = urdf;
    s.urdf_name = name;
    s.planner(params.clearance);
  } catch (const arm::ArmModelError& e) {
    throw LiftTestError(std::string("lift test: ") + e.what());
  } catch (const std::invalid_argument& e) {  // a robot reach planning cannot check
    throw LiftTestError(std::string("lift test: ") + e.what());
  }
  s.obstacles = motion::ReachPlanner::obstacles(octree_of(pieces.grid));

  // The world: the robot, the table and the object (its boxes, or its hull and its boxes' base).
  try {
    s.mjcf = robot_world_mjcf(urdf, name, WorldObject{pieces.boxes, convex ? hull.vertices : std::vector<Eigen::Vector3d>{},
                                                      params.mass, pieces.centroid, pieces.inertia, params.friction});
  } catch (const RobotWorldError& e) {
    throw LiftTestError(std::string("lift test: ") + e.what());
  }
  s.compile(s.planner(params.clearance).arm().joint_names());
}

LiftTest::~LiftTest() = default;

const TriangleMesh& LiftTest::object() const { return impl_->object; }
const ObjectPieces& LiftTest::pieces() const { return impl_->pieces; }

std::string describe(const ObjectPieces& p) {
  const double share = 100 * p.mesh_volume / p.hull_volume;
  if (p.hull)
    return fmt::format("MuJoCo collides it as its convex hull: the mesh is convex ({:.1f} cm^3, {:.1f}% of its hull's)",
                       p.mesh_volume * 1e6, share);
  return fmt::format("MuJoCo collides it as {} boxes of {:.1f} mm voxels, volume IoU {:.4f} against the mesh ({:.1f} of {:.1f} cm^3; "
                     "{:.1f}% of its hull's: not convex)",
                     p.boxes, p.voxel_size * 1e3, p.iou, p.volume * 1e6, p.mesh_volume * 1e6, share);
}
double LiftTest::simulated_s() const { return static_cast<double>(impl_->steps) * impl_->m->opt.timestep; }
long LiftTest::steps() const { return impl_->steps; }
const std::string& LiftTest::plan_note() const { return impl_->plan_note; }
const std::string& LiftTest::world_mjcf() const { return impl_->mjcf; }
const std::vector<std::string>& LiftTest::arm_joints() const { return impl_->arm_names; }
Eigen::VectorXd LiftTest::start_joints() const { return impl_->start; }

Eigen::Isometry3d LiftTest::body_pose(const std::string& link, const Eigen::VectorXd& joints) {
  auto& s = *impl_;
  if (joints.size() != static_cast<Eigen::Index>(s.arm_qpos.size()))
    throw std::invalid_argument("lift test: " + std::to_string(joints.size()) + " joint positions given, the arm has " +
                                std::to_string(s.arm_qpos.size()));
  mj_resetData(s.m, s.d);
  s.pose(joints, 0, s.spread_min);
  return s.body_pose(s.id(mjOBJ_BODY, link));
}

void LiftTest::stop() { impl_->stop.store(true); }

GraspExecution LiftTest::run(const Grasp& grasp) {
  auto& s = *impl_;
  for (const auto& c : grasp.contacts)
    if (!c.position.allFinite() || !c.normal.allFinite())
      throw std::invalid_argument("lift test: a grasp contact has a non-finite position or normal");
  if (!grasp.approach.allFinite() || grasp.approach.norm() < 1e-9)
    throw std::invalid_argument("lift test: the grasp's approach direction is zero or not finite");
  if (!std::isfinite(grasp.aperture)) throw std::invalid_argument("lift test: the grasp's aperture is not finite");
  s.plan_note.clear();
  s.steps = 0;
  if (s.stop.load()) return execute({}, {}, &grasp);
  // Standing in for the motion stage: the pregrasp opened a centimetre a side wider at a time
  // while the way in meets the object (a finger whose contact normal is far from its closing
  // direction passes the surface closer than its contact), up to the hand's widest.
  const double widest = 2 * (s.knuckle_x - s.pad_radius);
  motion::ReachPlan plan;
  for (double clearance = s.params.clearance;; clearance += 0.01) {
    plan = s.planner(clearance).plan(grasp, s.obstacles, s.start);
    const bool object_in_the_way = plan.refusal == motion::Refusal::Approach || plan.refusal == motion::Refusal::Collision;
    if (plan.ok || !object_in_the_way || plan.opening >= widest - 1e-9) break;
  }
  if (!plan.ok) {
    GraspExecution result;
    result.reason = std::string("the arm cannot take the grasp (") + motion::to_string(plan.refusal) + "): " + plan.why;
    s.plan_note = "refused";
    return result;
  }
  s.plan_note = fmt::format("{:.2f} s of motion, path {:.2f} rad{}, planned in {:.3f} s", plan.trajectory.points.back().time,
                            plan.figures.path_length, plan.figures.direct ? " (straight)" : "", plan.figures.planning_s);
  return execute(plan.trajectory, plan.hand, &grasp);
}

GraspExecution LiftTest::execute(const JointTrajectory& trajectory, const std::vector<HandCommand>& commands, const Grasp* planned) {
  auto& s = *impl_;
  s.steps = 0;
  try {
    if (s.stop.load()) throw Impl::Stopped{};
    return run_steps(trajectory, commands, planned);
  } catch (const Impl::Stopped&) {
    // Open the hand: every closing slide back to its stop, and the simulation ends there.
    for (int i = 0; i < static_cast<int>(0.2 / s.m->opt.timestep); ++i) {
      for (const auto& finger : s.fingers) s.d->ctrl[finger.close_actuator] = -s.params.finger_force * finger.gear;
      mj_step(s.m, s.d);
      ++s.steps;
    }
    GraspExecution result;
    result.reason = "stopped (safe state): the hand opened and the simulation ended";
    return result;
  }
}

// One execution of a reach plan in the world: the arm's reference, the hand's commands and state,
// and the stages from the set-up to the verdict, which `result` gathers.
struct LiftTest::Impl::Run {
  Impl& s;
  Reference reference;
  std::vector<HandCommand> schedule;  // the hand's commands in time order
  double close_time = INFINITY;       // the first close's time on the trajectory
  Phases phases;
  double end = 0;  // where the verdict ends on the trajectory
  // The hand's state: open by open_travel with the fingers `spread` apart, or closing with `force`.
  bool closing = false;
  HandCommand::Mode mode = HandCommand::Mode::Basic;
  double open_travel = 0, spread = 0, force = 0;
  double t0 = 0;  // the trajectory's start on the simulation's clock
  std::size_t next_command = 0;
  Eigen::VectorXd q_ref, v_ref, a_ref;
  std::vector<mjtNum> acc, torque;  // the arm's computed torque, per degree of freedom
  Eigen::Vector3d start;            // the object's centre, settled on the table
  bool lost = false;                // the object went out of the hand, or the simulation went wrong
  double close_started = 0;  // the close's time on the simulation's clock
  // Where each closing slide stopped on the object (NaN until it has).
  std::array<double, 3> stopped_at{NAN, NAN, NAN};
  GraspExecution result;

  // Reads the plan: the close's time, the stretches after it, the verdict's end, and the hand's
  // state before the trajectory starts (a first open at time 0 sets it).
  Run(Impl& impl, const JointTrajectory& trajectory, const std::vector<HandCommand>& commands)
      : s(impl),
        reference(trajectory, impl.arm_columns(trajectory)),
        schedule(commands),
        spread(impl.spread_min),
        force(impl.params.finger_force),
        acc(static_cast<std::size_t>(impl.m->nv), 0),
        torque(static_cast<std::size_t>(impl.m->nv), 0) {
    std::stable_sort(schedule.begin(), schedule.end(), [](const HandCommand& a, const HandCommand& b) { return a.time < b.time; });
    for (const auto& c : schedule)
      if (c.action == HandCommand::Action::Close) {
        close_time = c.time;
        break;
      }
    phases = phases_after(reference, close_time);
    // A release before the hold's end ends the verdict there.
    end = std::isfinite(close_time) ? phases.hold_end : reference.end();
    for (const auto& c : schedule)
      if (c.action == HandCommand::Action::Open && c.time > close_time) end = std::min(end, c.time);
    if (!schedule.empty() && schedule.front().action == HandCommand::Action::Open && schedule.front().time <= 0) {
      open_travel = s.travel_for(schedule.front().opening / 2);
      spread = schedule.front().spread;
    }
  }

  // The world at the trajectory's start, so that every run begins alike: the robot posed at the
  // first waypoint, then the object settled on the table while the arm holds still.
  void set_up() {
    s.steps = 0;
    mj_resetData(s.m, s.d);
    for (int g = 0; g < s.m->ngeom; ++g) s.m->geom_friction[3 * g] = s.params.friction;
    reference.sample(0, q_ref, v_ref, a_ref);
    s.pose(q_ref, open_travel, spread);
    for (int i = 0; i < static_cast<int>(kSettle_s / s.m->opt.timestep); ++i) step(false);
    start = s.object_centre();
    t0 = s.d->time;
  }

  // One physics step: following the trajectory, the reference and the commands due now; then the
  // arm's and the hand's controls. A stop ends the run here.
  void step(bool follow) {
    mj_step1(s.m, s.d);
    if (follow) {
      const double t = s.d->time - t0;
      reference.sample(t, q_ref, v_ref, a_ref);
      take_commands(t);
    }
    drive_arm();
    drive_hand();
    if (s.stop.load()) throw Stopped{};
    mj_step2(s.m, s.d);
    ++s.steps;
  }

  // The hand's commands whose time on the trajectory has come, in order, into the hand's state.
  void take_commands(double t) {
    for (; next_command < schedule.size() && schedule[next_command].time <= t + 1e-9; ++next_command) {
      const HandCommand& c = schedule[next_command];
      mode = c.mode;
      if (c.action == HandCommand::Action::Open) {
        closing = false;
        open_travel = s.travel_for(c.opening / 2);
        spread = s.spread_for(c);
      } else {
        if (!closing) close_started = s.d->time;
        closing = true;
        force = robotiq::grip_force(c.force > 0 ? c.force : s.params.finger_force);  // as hw.robotiq_3f does
      }
    }
  }

  // The arm follows the reference: computed torque within the effort limits.
  void drive_arm() {
    mjModel* m = s.m;
    mjData* d = s.d;
    std::fill(acc.begin(), acc.end(), 0.0);
    for (std::size_t i = 0; i < s.arm_dof.size(); ++i) {
      const auto k = static_cast<Eigen::Index>(i);
      const int dof = s.arm_dof[i];
      acc[static_cast<std::size_t>(dof)] =
          a_ref(k) + kArmKp * (q_ref(k) - d->qpos[s.arm_qpos[i]]) + kArmKd * (v_ref(k) - d->qvel[dof]);
    }
    mj_mulM(m, d, torque.data(), acc.data());
    for (std::size_t i = 0; i < s.arm_dof.size(); ++i) {
      const int dof = s.arm_dof[i];
      d->ctrl[s.arm_actuator[i]] = std::clamp(torque[static_cast<std::size_t>(dof)] + d->qfrc_bias[dof], -s.arm_effort[i], s.arm_effort[i]);
    }
  }

  // The hand in its state: the closing slides hold the opening, or push with the force until they
  // stop on the object and then keep their place there; in scissor mode the thumb stays open and
  // the two fingers close on each other with it.
  void drive_hand() {
    mjModel* m = s.m;
    mjData* d = s.d;
    const bool scissor = mode == HandCommand::Mode::Scissor;
    for (std::size_t f = 0; f < 3; ++f) {
      const auto& finger = s.fingers[f];
      const double limit = force * finger.gear;
      const bool pushes = closing && !scissor;
      const double q = d->qpos[m->jnt_qposadr[finger.close_joint]];
      const double v = d->qvel[m->jnt_dofadr[finger.close_joint]];
      double& ctrl = d->ctrl[finger.close_actuator];
      if (!pushes) {
        stopped_at[f] = NAN;
        ctrl = std::clamp(kHoldGain * (open_travel - q), -limit, limit);
      } else {
        if (std::isnan(stopped_at[f]) && d->time - close_started >= kStartup && v < kStoppedSpeed) stopped_at[f] = q;
        const double stall = robotiq::kMaxForce * finger.gear;
        ctrl = std::isnan(stopped_at[f]) ? limit : std::clamp(limit + kStopStiffness * (stopped_at[f] - q), -stall, stall);
      }
      if (finger.spread_actuator >= 0) {
        const double half = (closing && scissor ? 0.0 : std::clamp(spread, s.spread_min, s.spread_max) / 2);
        d->ctrl[finger.spread_actuator] = f == 1 ? half : -half;
        m->actuator_forcerange[2 * finger.spread_actuator + 1] = closing && scissor ? force : s.spread_force;
        m->actuator_forcerange[2 * finger.spread_actuator] = -(closing && scissor ? force : s.spread_force);
      }
    }
  }

  // Follows the trajectory until `until` on it, calling `each` after every step: false from it
  // ends the stretch early (and run_until returns false).
  bool run_until(double until, const std::function<bool()>& each) {
    while (s.d->time - t0 < until - 1e-9) {
      step(true);
      if (!each()) return false;
    }
    return true;
  }

  std::string when() const { return seconds(s.d->time - t0); }

  // The way in: until the fingers close, any contact of the robot with the table or the object is
  // a collision, and the test's failure.
  bool clear_until_close() {
    std::string hit;
    const bool clear = run_until(std::min(close_time, end), [&] {
      hit = s.robot_collision();
      return hit.empty();
    });
    if (!clear) result.reason = "collision before the fingers closed, at " + when() + " on the trajectory: " + hit;
    return clear;
  }

  // The fingers close while the arm waits; the hand's contacts with the object when the lift
  // begins are the grasp it took.
  bool close() {
    if (!std::isfinite(close_time)) {
      result.reason = "the hand was not told to close";
      return false;
    }
    run_until(std::min(phases.lift_start, end), [] { return true; });
    if (s.unstable()) {
      result.reason = "the simulation became unstable at " + when();
      return false;
    }
    result.contacts = s.object_contacts();
    if (result.contacts.empty()) {
      result.reason = "no contact with the object after closing the fingers (" + when() + ")";
      return false;
    }
    return true;
  }

  // Whether the hand took the planned grasp, not another one (a wide-open hand can close around
  // the whole object). Where along its length a finger touches does not matter, so the distance is
  // measured across the approach.
  bool took(const Grasp& planned) {
    const Eigen::Vector3d a = planned.approach.normalized();
    const Eigen::Vector3d thumb = planned.contacts[0].position;
    const Eigen::Vector3d mid = (planned.contacts[1].position + planned.contacts[2].position) / 2;
    const Eigen::Vector3d y = a.cross(((mid - thumb) - a * a.dot(mid - thumb)).normalized());
    // finger_a is on the palm's +y side.
    std::array<Eigen::Vector3d, 3> at = {thumb, planned.contacts[1].position, planned.contacts[2].position};
    if ((at[1] - mid).dot(y) < (at[2] - mid).dot(y)) std::swap(at[1], at[2]);
    for (std::size_t f = 0; f < 3; ++f) {
      double nearest = INFINITY;
      for (const auto& c : result.contacts) {
        if (c.link.rfind(s.fingers[f].name + "_", 0) != 0) continue;
        const Eigen::Vector3d off = c.position - at[f];
        nearest = std::min(nearest, (off - a * a.dot(off)).norm());
      }
      if (nearest > s.params.contact_tolerance) {
        result.reason = std::isinf(nearest) ? s.fingers[f].name + " did not touch the object"
                                            : fmt::format("{} touched the object {:.3f} m (across the approach) from its planned "
                                                          "contact, more than the {:.3f} m allowed: not the planned grasp",
                                                          s.fingers[f].name, nearest, s.params.contact_tolerance);
        return false;
      }
    }
    return true;
  }

  // Whether the object is still in the hand while it does `phase`: moved no more than the drop
  // distance relative to the palm since `grasped`; else the reason, and the object is lost.
  bool in_hand(const char* phase, const Eigen::Vector3d& grasped) {
    auto moved = [&] { return (s.in_palm(s.object_centre()) - grasped).norm(); };
    if (s.unstable()) {
      result.reason = "the simulation became unstable at " + when();
      return !(lost = true);
    }
    if (moved() <= s.params.drop_distance) return true;
    result.reason = fmt::format("dropped at {} while {} (moved {:.3f} m in the hand)", when(), phase, moved());
    return !(lost = true);
  }

  // The verdict: the lift, then the hold; held when the object stayed in the hand and rose with it.
  void lift_and_hold() {
    const Eigen::Vector3d grasped = s.in_palm(s.object_centre());
    const double palm_start = s.body_pose(s.palm_body).translation().z();
    run_until(std::min(phases.lift_end, end), [&] { return in_hand("lifting", grasped); });
    const Eigen::Vector3d hold_start = s.in_palm(s.object_centre());
    const double held_from = s.d->time;
    if (!lost) run_until(end, [&] { return in_hand("holding", grasped); });
    result.hold_s = std::max(0.0, s.d->time - held_from - (lost ? s.m->opt.timestep : 0.0));
    result.slip_m = (s.in_palm(s.object_centre()) - hold_start).norm();
    result.lift_height_m = s.object_centre().z() - start.z();
    const double palm_rise = s.body_pose(s.palm_body).translation().z() - palm_start;
    result.held = !lost && palm_rise > 1e-3 && result.lift_height_m >= palm_rise / 2;
    if (!lost && !result.held)
      result.reason = palm_rise > 1e-3 ? fmt::format("the object rose only {:.3f} m of the hand's {:.3f} m", result.lift_height_m, palm_rise)
                                       : "the arm did not lift the hand after closing";
  }
};

GraspExecution LiftTest::run_steps(const JointTrajectory& trajectory, const std::vector<HandCommand>& commands, const Grasp* planned) {
  Impl::Run run(*impl_, trajectory, commands);
  run.set_up();
  if (run.clear_until_close() && run.close() && (!planned || run.took(*planned))) run.lift_and_hold();
  return run.result;
}

}  // namespace fba::sim_hand
