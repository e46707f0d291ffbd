// The lift test in one world: the whole robot generated from its URDF, the table and the object as
// boxes. The world agrees with KDL on where each part is; the arm follows reach planning's
// trajectory and holds a box; a bad grasp drops; a U is not held where only its hull would be; a
// sweep through the object before the fingers close is the failure's reason.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include "fba/geometry/mesh_io.hpp"
#include "fba/geometry/object_families.hpp"
#include "fba/motion/hand_geometry.hpp"
#include "lift_test.hpp"
#include "ring_grasp.hpp"
#include "scenes.hpp"
#include "support/build_paths.hpp"
#include "support/data_sets.hpp"
#include "support/u_shape.hpp"
#include "support/wrist_camera_arm.hpp"

namespace {

using fba::sim_hand::LiftTest;
using fba::sim_hand::LiftTestError;
using fba::sim_hand::LiftTestParams;
using namespace fba::sim_hand::test;

using fba::test::kCan;
constexpr double kDegree = M_PI / 180;

const fba::TriangleMesh& can() {
  static const fba::TriangleMesh mesh = fba::geometry::load_mesh(kCan);
  return mesh;
}

double mid_height(const fba::TriangleMesh& placed) { return fba::geometry::mesh_bounds(placed).center().z(); }

const Eigen::Vector3d kBox(0.06, 0.06, 0.10);

std::string urdf_text() {
  std::ifstream in(fba::test::wrist_camera_arm_urdf());
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// Where KDL puts `link` (the URDF's chain from the world) and where MuJoCo's generated world has it,
// at the arm's joints q and the hand open (every hand joint at 0 but the scissor at its narrowest).
void expect_same_pose(LiftTest& test, const std::string& urdf, const std::string& link, const Eigen::VectorXd& q) {
  const fba::arm::ArmModel chain = fba::arm::ArmModel::from_string(urdf, "urdf", "world", link);
  Eigen::VectorXd all = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(chain.size()));
  all.head(6) = q;
  for (std::size_t i = 6; i < chain.size(); ++i)
    if (chain.joint_names()[i] == "finger_a_spread") all(static_cast<Eigen::Index>(i)) = 0.01;
  const Eigen::Isometry3d kdl = chain.forward(all);
  const Eigen::Isometry3d mujoco = test.body_pose(link, q);
  EXPECT_LT((kdl.translation() - mujoco.translation()).norm(), 1e-6) << link << " at " << q.transpose();
  EXPECT_LT(fba::arm::angle_between(kdl, mujoco), 1e-6) << link << " at " << q.transpose();
}

}  // namespace

// The world is generated from the URDF, so KDL (the planner's kinematics) and MuJoCo put the
// flange, the palm, the camera and a pad at the same place for any joints, and with a profile's
// measured transforms too.
TEST(RobotWorld, TheGeneratedWorldAndTheUrdfAgreeOnEveryPart) {
  LiftTest test(box_mesh(kBox), {});
  std::mt19937 random(7);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI);
  std::vector<Eigen::VectorXd> joints{Eigen::VectorXd::Zero(6), test.start_joints()};
  for (int i = 0; i < 4; ++i) joints.push_back(Eigen::VectorXd::NullaryExpr(6, [&] { return angle(random); }));
  for (const auto& q : joints)
    for (const char* link : {"wrist_3_link", "flange", "palm", "camera", "thumb_pad", "finger_a_pad"}) expect_same_pose(test, urdf_text(), link, q);

  fba::sim_hand::RobotSetup measured;
  measured.origins["flange_to_palm"] = fba::arm::pose_from_xyz_rpy({0.002, -0.001, 0.08, 0.01, 0, 0.2}, "flange_to_palm");
  measured.origins["flange_to_camera"] = fba::arm::pose_from_xyz_rpy({0.01, 0.065, 0.028, 0, 0.02, 0}, "flange_to_camera");
  measured.origins["world_to_base"] = fba::arm::pose_from_xyz_rpy({-0.47, 0.02, 0.0, 0, 0, 0.05}, "base_pose");
  LiftTest moved(box_mesh(kBox), {}, {}, measured);
  const std::string urdf = fba::arm::with_fixed_joint_origins(urdf_text(), measured.origins);
  for (const auto& q : joints)
    for (const char* link : {"flange", "palm", "camera"}) expect_same_pose(moved, urdf, link, q);
}

// Reach planning's trajectory for a grasp from above on a 6 x 6 x 10 cm box before the arm, as
// motion.reach_planner sends it: the arm carries the hand there, the fingers close, the arm lifts
// the box and holds it.
TEST(LiftTest, ABoxBeforeTheArmIsHeldOnTheReachPlannersTrajectory) {
  LiftTest test(box_mesh(kBox), {});
  const fba::Grasp g = box_grasp(kBox, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.06);
  const auto plan = planner().plan(g, box_model(kBox), test.start_joints());
  ASSERT_TRUE(plan.ok) << plan.why;
  const auto r = test.execute(plan.trajectory, plan.hand, &g);
  EXPECT_TRUE(r.held) << r.reason;
  EXPECT_EQ(r.reason, "");
  EXPECT_NEAR(r.lift_height_m, 0.1, 0.01);
  EXPECT_LT(r.slip_m, 0.005);
  EXPECT_NEAR(r.hold_s, 2.0, 0.01);
  for (const std::string finger : {"thumb", "finger_a", "finger_b"}) {
    bool touches = false;
    for (const auto& c : r.contacts) touches |= c.link.rfind(finger, 0) == 0 && c.force > 0;
    EXPECT_TRUE(touches) << finger << " does not touch the box";
  }
  // The run ends with the hold: the plan's whole duration, and the object's settling before it.
  EXPECT_NEAR(test.simulated_s(), plan.trajectory.points.back().time + 0.2, 0.01);
}

// run() plans the reach itself, from the hand over the workspace, the true object as the model.
TEST(LiftTest, RunPlansTheReachAndTheRingGraspAroundTheCanHolds) {
  LiftTest test(can(), {0.03, -0.02, 20 * kDegree});
  const auto grasp = fba::sim_hand::ring_grasp(test.object(), mid_height(test.object()), 180 * kDegree);
  const auto r = test.run(grasp);
  EXPECT_TRUE(r.held) << r.reason;
  EXPECT_LT(r.slip_m, 0.005);
  EXPECT_NE(test.plan_note().find("s of motion"), std::string::npos) << test.plan_note();
  const Eigen::Vector3d centre = fba::geometry::mesh_bounds(test.object()).center();
  for (const auto& c : r.contacts) {
    Eigen::Vector3d to_axis = centre - c.position;
    to_axis.z() = 0;
    EXPECT_GT(c.normal.dot(to_axis.normalized()), 0.5) << c.link << ": the normal does not point into the can";
  }
}

// A ball, convex: the fingers touch its hull, smooth, and it stands where it was put (on its
// boxes' flat base) rather than rolling off its hull's lowest vertex before the hand arrives; the
// ring grasp around its equator holds it, each finger where it was planned.
TEST(LiftTest, ABallStandsWhereItWasPutAndTheRingGraspAroundItsEquatorHoldsIt) {
  // A generated ball (sampled on a cube's faces), turned as a drop might leave it: no vertex
  // straight below its centre.
  fba::TriangleMesh ball = fba::geometry::make_family_object(fba::geometry::ObjectFamily::sphere, 31, 1).mesh;
  const Eigen::Matrix3f turn = Eigen::AngleAxisf(0.7f, Eigen::Vector3f(1, 2, 3).normalized()).toRotationMatrix();
  for (auto& v : ball.vertices) v = turn * v;
  LiftTest test(ball, {0.01, 0.02, 0});
  EXPECT_TRUE(test.pieces().hull);
  const auto r = test.run(fba::sim_hand::ring_grasp(test.object(), mid_height(test.object()), 180 * kDegree));
  EXPECT_TRUE(r.held) << r.reason;
  EXPECT_LT(r.slip_m, 0.005);
}

// A generated superquadric in a rest a drop left it in (seed 31's superquadric-04, its first rest),
// turned 305 degrees: its footprint on the table is a polygon of many voxel corners. On their convex
// hull alone MuJoCo kept one to three contacts that moved about the base, and the object walked 2
// cm across the table before the hand came: the thumb met it on the way in. The grasp is the one
// the loop selected there (its contacts pinned by two views, force closure on the mesh).
TEST(LiftTest, ASuperquadricOnItsFlatBaseStaysWhereItWasPutAndTheGraspPlannedOnItHolds) {
  fba::TriangleMesh mesh = fba::geometry::make_family_object(fba::geometry::ObjectFamily::superquadric, 31, 4).mesh;
  const Eigen::Matrix3f rest = Eigen::Quaternionf(0.389969f, 0.554366f, 0.735257f, 0.0f).normalized().toRotationMatrix();
  for (auto& v : mesh.vertices) v = rest * v;
  LiftTest test(mesh, {-0.013, 0.0, 305 * kDegree});
  ASSERT_TRUE(test.pieces().hull);
  fba::Grasp g;
  g.contacts = {fba::GraspContact{{-0.027862, -0.023601, 0.018826}, {0.580366, 0.780095, 0.233724}},
                fba::GraspContact{{-0.022255, 0.027750, 0.026681}, {0.128123, -0.990278, -0.054162}},
                fba::GraspContact{{0.016452, 0.008273, 0.034934}, {-0.758159, -0.555973, -0.340719}}};
  g.approach = Eigen::Vector3d(0.263393, 0.117713, -0.957480);
  g.aperture = 0.069982;
  g.spread = 0.044110;
  g.pinch_depth = 0.015;
  const auto r = test.run(g);
  EXPECT_TRUE(r.held) << r.reason;
}

// A ball 11 cm across (seed 31's sphere-09 in its first rest) taken with the hand tilted 32 degrees
// from straight down, as the loop selected it there: the weight has a share along the squeeze.
// The fingers stop where they meet the ball and keep their place, as the Robotiq's do, so the ball
// stays put in the hand; fingers that only pushed with their force would let the ball and the
// three of them slide together across the hand, 3 cm within a second of the hold.
TEST(LiftTest, ABallTakenWithTheSqueezeSlopingStaysPutBetweenTheStoppedFingers) {
  fba::TriangleMesh mesh = fba::geometry::make_family_object(fba::geometry::ObjectFamily::sphere, 31, 9).mesh;
  const Eigen::Matrix3f rest = Eigen::Quaternionf(0.613425f, -0.669501f, 0.4189f, 0.0f).normalized().toRotationMatrix();
  for (auto& v : mesh.vertices) v = rest * v;
  LiftTest test(mesh, {0.008, -0.009, 224 * kDegree});
  fba::Grasp g;
  g.contacts = {fba::GraspContact{{-0.041915, -0.026799, 0.038636}, {0.938034, 0.285448, 0.196500}},
                fba::GraspContact{{0.040107, 0.035779, 0.059160}, {-0.550935, -0.832249, -0.061901}},
                fba::GraspContact{{0.052304, -0.022238, 0.085326}, {-0.848236, 0.175879, -0.499562}}};
  g.approach = Eigen::Vector3d(0.435952, -0.292226, -0.851205);
  g.aperture = 0.120108;
  g.spread = 0.064803;
  const auto r = test.run(g);
  EXPECT_TRUE(r.held) << r.reason;
  EXPECT_LT(r.slip_m, 0.001);
}

// A plate 1.3 cm tall pinched 6.5 mm above the table, the contacts 3 mm short of the fingertips'
// flat ends (each end 3.5 mm above the table): lifted and held. A fingertip rounded as the rest of
// the finger (1 cm) would meet the plate's sides no lower than 13 mm above the table, on its edge.
TEST(LiftTest, APlateLowerThanAFingertipsRadiusIsPinchedByTheFlatFingertipsAndHeld) {
  const Eigen::Vector3d plate(0.07, 0.09, 0.013);
  LiftTest test(box_mesh(plate), {});
  fba::Grasp g = box_grasp(plate, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.0065);
  g.pinch_depth = fba::motion::hand::kDeepestPinch;
  const auto r = test.run(g);
  EXPECT_TRUE(r.held) << r.reason;
  EXPECT_EQ(r.contacts.size(), 3u);
}

// The same grasp 20 cm above the box: the fingers close on the air.
TEST(LiftTest, AGraspThatClosesInTheAirFindsNoContact) {
  LiftTest test(box_mesh(kBox), {});
  fba::Grasp g = box_grasp(kBox, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.06);
  for (auto& c : g.contacts) c.position.z() += 0.2;
  const auto r = test.run(g);
  EXPECT_FALSE(r.held);
  EXPECT_TRUE(r.contacts.empty());
  EXPECT_NE(r.reason.find("no contact with the object after closing the fingers"), std::string::npos) << r.reason;
}

// A 1.2 kg bar 24 cm long taken near one end: the fingers' friction cannot hold its turn about the
// squeeze, and it swings out of the hand as the arm lifts.
TEST(LiftTest, ContactsOffCentreOnAHeavyBarDrop) {
  const Eigen::Vector3d bar(0.24, 0.06, 0.06);
  LiftTestParams p;
  p.mass = 1.2;
  LiftTest test(box_mesh(bar), {}, p);
  const fba::Grasp g = box_grasp(bar, Eigen::Vector3d::UnitY(), -Eigen::Vector3d::UnitZ(), 0.03, 0.09);
  const auto r = test.run(g);
  EXPECT_FALSE(r.held);
  EXPECT_NE(r.reason.find("dropped at t="), std::string::npos) << r.reason;
  // Centred, the same bar holds.
  const auto centred = test.run(box_grasp(bar, Eigen::Vector3d::UnitY(), -Eigen::Vector3d::UnitZ(), 0.03));
  EXPECT_TRUE(centred.held) << centred.reason;
}

// A U standing on the table, its gap between the walls open upwards and at both ends. A grasp on
// its ends' faces across the gap: on the convex hull, which fills the gap, the fingers would meet
// those faces and hold; on the U itself (as boxes: it is not convex) they close through the gap on
// nothing. The solid block the hull is (convex: collided as its hull) holds with the same grasp.
TEST(LiftTest, AConcaveObjectIsNotHeldWhereOnlyItsHullWouldBe) {
  const fba::test::UShape u;
  const fba::Grasp g = box_grasp(Eigen::Vector3d(u.width, u.length, u.height), Eigen::Vector3d::UnitY(), -Eigen::Vector3d::UnitZ(), 0.07);
  LiftTestParams p;
  p.voxel_size = 0.005;  // the U's walls and base are whole voxels
  LiftTest concave(fba::test::make_u_shape(u), {}, p);
  EXPECT_FALSE(concave.pieces().hull);  // boxes: its volume is two thirds of its hull's
  EXPECT_GT(concave.pieces().iou, 0.99);
  const auto r = concave.run(g);
  EXPECT_FALSE(r.held);
  EXPECT_NE(r.reason.find("no contact with the object"), std::string::npos) << r.reason;

  LiftTest hull(box_mesh(Eigen::Vector3d(u.width, u.length, u.height)), {}, p);
  EXPECT_TRUE(hull.pieces().hull);  // convex: its hull, exactly
  EXPECT_NEAR(hull.pieces().hull_volume, u.width * u.length * u.height, 1e-9);
  const auto h = hull.run(g);
  EXPECT_TRUE(h.held) << h.reason;
}

// A trajectory (not reach planning's) that sweeps the open hand sideways through the box at its
// mid height: the first touch is the failure, before any finger closes.
TEST(LiftTest, ASweepThroughTheObjectBeforeTheCloseIsTheFailure) {
  LiftTest test(box_mesh(kBox), {});
  std::vector<Eigen::VectorXd> q;
  Eigen::VectorXd seed = test.start_joints();
  for (double x = -0.3; x <= 0.3 + 1e-9; x += 0.02) {
    q.push_back(joints_for_palm(palm_down(Eigen::Vector3d(x, 0, 0.05 + 0.15)), seed));
    ASSERT_EQ(q.back().size(), 6) << "no IK solution at x = " << x;
    seed = q.back();
  }
  const auto r = test.execute(through(q, 0.1, test.arm_joints()), open_then_close(3.0));  // closes after the sweep
  EXPECT_FALSE(r.held);
  EXPECT_EQ(r.reason.rfind("collision before the fingers closed, at t=", 0), 0u) << r.reason;
  EXPECT_NE(r.reason.find("touches the object at ("), std::string::npos) << r.reason;  // where, in the world
}

TEST(LiftTest, EachRunStartsAfreshAndGivesTheSameResult) {
  LiftTest test(box_mesh(kBox), {});
  const fba::Grasp g = box_grasp(kBox, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.06);
  const auto a = test.run(g);
  const long steps = test.steps();
  const auto b = test.run(g);
  EXPECT_EQ(test.steps(), steps);
  EXPECT_EQ(a.held, b.held);
  EXPECT_DOUBLE_EQ(a.slip_m, b.slip_m);
  EXPECT_DOUBLE_EQ(a.lift_height_m, b.lift_height_m);
  EXPECT_EQ(a.contacts.size(), b.contacts.size());
}

// A grasp the arm cannot take: the hand would come from under the table. Reach planning's refusal
// is the reason, and nothing is simulated.
TEST(LiftTest, AGraspTheArmCannotTakeFailsWithThePlannersReason) {
  LiftTest test(box_mesh(kBox), {});
  const fba::Grasp g = box_grasp(kBox, Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitZ(), 0.06);
  const auto r = test.run(g);
  EXPECT_FALSE(r.held);
  EXPECT_EQ(r.reason.rfind("the arm cannot take the grasp (table): ", 0), 0u) << r.reason;
  EXPECT_EQ(test.steps(), 0);
}

TEST(LiftTest, ATrajectoryForOtherJointsIsRefusedByName) {
  LiftTest test(box_mesh(kBox), {});
  fba::JointTrajectory t;
  t.names = {"elbow"};
  t.points.push_back({0, {0}, {0}});
  try {
    test.execute(t, {});
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("the trajectory has no joint 'shoulder_pan_joint' of the arm's"), std::string::npos) << e.what();
  }
}

// The safe state: the hand opens and the simulation ends; later runs end at once.
TEST(LiftTest, AfterStopNoGraspIsExecuted) {
  LiftTest test(box_mesh(kBox), {});
  test.stop();
  const auto r = test.run(box_grasp(kBox, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.06));
  EXPECT_FALSE(r.held);
  EXPECT_NE(r.reason.find("safe state"), std::string::npos) << r.reason;
}

TEST(LiftTest, NonFiniteGraspIsRefused) {
  LiftTest test(box_mesh(kBox), {});
  fba::Grasp g = box_grasp(kBox, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.06);
  g.contacts[1].position.x() = NAN;
  EXPECT_THROW(test.run(g), std::invalid_argument);
  g = box_grasp(kBox, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.06);
  g.approach.setZero();
  EXPECT_THROW(test.run(g), std::invalid_argument);
}

// The hand grips with 15 to 60 N (hw.robotiq_3f's range); a lift test asked to close otherwise would
// judge a grasp on a hand that does not exist.
TEST(LiftTest, AFingerForceTheHandCannotGiveIsAClearError) {
  for (const double newtons : {10.0, 61.0, double(NAN)}) {
    LiftTestParams p;
    p.finger_force = newtons;
    try {
      LiftTest test(box_mesh(kBox), {}, p);
      FAIL() << "no error at " << newtons << " N";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("within the hand's 15 to 60 N"), std::string::npos) << e.what();
    }
  }
}

TEST(LiftTest, EmptyMeshIsAClearError) {
  try {
    LiftTest test(fba::TriangleMesh{}, {});
    FAIL() << "no error";
  } catch (const LiftTestError& e) {
    EXPECT_NE(std::string(e.what()).find("no triangles"), std::string::npos) << e.what();
  }
}

// A robot the world cannot be made of: a link that collides as a mesh file, named.
TEST(LiftTest, ARobotWithAMeshShapeIsAClearError) {
  fba::sim_hand::RobotSetup robot;
  robot.urdf = urdf_text();
  const std::string camera_box = R"(<collision><origin xyz="0 0 -0.015"/><geometry><box size="0.09 0.025 0.03"/></geometry></collision>)";
  const auto at = robot.urdf.find(camera_box);
  ASSERT_NE(at, std::string::npos);
  robot.urdf.replace(at, camera_box.size(), R"(<collision><geometry><mesh filename="camera.stl"/></geometry></collision>)");
  try {
    LiftTest test(box_mesh(kBox), {}, {}, robot);
    FAIL() << "no error";
  } catch (const LiftTestError& e) {
    EXPECT_NE(std::string(e.what()).find("link 'camera' collides as"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("camera.stl"), std::string::npos) << e.what();
  }
}

TEST(LiftTest, TheBuiltInRobotIsTheUrdfFile) { EXPECT_EQ(LiftTest::robot_urdf(), urdf_text()); }
