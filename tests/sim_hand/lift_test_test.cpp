// The lift test on the YCB can: a grasp whose answer is known (three contacts 120 degrees apart at
// mid height holds; contacts all on one side, above the object, or under the table do not), and
// clear errors for a scene that cannot be built.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include "fba/geometry/mesh_io.hpp"
#include "lift_test.hpp"
#include "ring_grasp.hpp"
#include "support/build_paths.hpp"
#include "support/data_sets.hpp"
#include "support/mesh_files.hpp"
#include "support/temp_dir.hpp"

namespace {

using fba::sim_hand::LiftTest;
using fba::sim_hand::LiftTestError;
using fba::sim_hand::LiftTestParams;
using fba::sim_hand::ObjectPlacement;

using fba::test::kCan;
constexpr double kDegree = M_PI / 180;

const fba::TriangleMesh& can() {
  static const fba::TriangleMesh mesh = fba::geometry::load_mesh(kCan);
  return mesh;
}

double mid_height(const fba::TriangleMesh& placed) { return fba::geometry::mesh_bounds(placed).center().z(); }

// Contacts on the can's side at the given angles about its axis, at mid height, from above.
fba::Grasp grasp_at_angles(const LiftTest& test, double thumb, double finger_a, double finger_b) {
  const auto box = fba::geometry::mesh_bounds(test.object());
  const Eigen::Vector3d axis(box.center().x(), box.center().y(), box.center().z());
  const double radius = box.sizes().x() / 2;
  fba::Grasp g;
  const double angles[3] = {thumb, finger_a, finger_b};
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d out(std::cos(angles[i]), std::sin(angles[i]), 0);
    g.contacts[static_cast<std::size_t>(i)].position = axis + radius * out;
    g.contacts[static_cast<std::size_t>(i)].normal = -out;
  }
  g.approach = -Eigen::Vector3d::UnitZ();
  g.spread = (g.contacts[1].position - g.contacts[2].position).norm();
  g.aperture = ((g.contacts[1].position + g.contacts[2].position) / 2 - g.contacts[0].position).norm() + 0.04;
  return g;
}

TEST(LiftTest, RingGraspAroundTheCanAtMidHeightHolds) {
  LiftTest test(can(), {});
  const auto grasp = fba::sim_hand::ring_grasp(test.object(), mid_height(test.object()), 180 * kDegree);
  const auto r = test.run(grasp);
  EXPECT_TRUE(r.held) << r.reason;
  EXPECT_TRUE(r.reason.empty()) << r.reason;
  EXPECT_LT(r.slip_m, 0.005);
  EXPECT_NEAR(r.lift_height_m, 0.1, 0.01);
  EXPECT_DOUBLE_EQ(r.hold_s, 2.0);
  // Every finger touches the object, pushing into it.
  for (const std::string finger : {"thumb", "finger_a", "finger_b"}) {
    bool touches = false;
    for (const auto& c : r.contacts) touches |= c.link.rfind(finger, 0) == 0 && c.force > 0;
    EXPECT_TRUE(touches) << finger << " does not touch the can";
  }
  const Eigen::Vector3d centre = fba::geometry::mesh_bounds(test.object()).center();
  for (const auto& c : r.contacts) {
    Eigen::Vector3d to_axis = centre - c.position;
    to_axis.z() = 0;
    EXPECT_GT(c.normal.dot(to_axis.normalized()), 0.5) << c.link << ": the normal does not point into the can";
  }
}

TEST(LiftTest, GraspIsInTheTableFrameWhereverTheObjectStands) {
  LiftTest test(can(), {0.15, -0.1, 35 * kDegree});
  const auto box = fba::geometry::mesh_bounds(test.object());
  EXPECT_NEAR(box.min().z(), 0.0, 1e-6);  // it rests on the table
  EXPECT_NEAR(box.center().x(), 0.15, 0.02);
  const auto r = test.run(fba::sim_hand::ring_grasp(test.object(), mid_height(test.object()), 70 * kDegree));
  EXPECT_TRUE(r.held) << r.reason;
}

TEST(LiftTest, EachRunStartsAfreshAndGivesTheSameResult) {
  LiftTest test(can(), {});
  const auto grasp = fba::sim_hand::ring_grasp(test.object(), mid_height(test.object()), 0);
  const auto a = test.run(grasp);
  const long steps = test.steps();
  const auto b = test.run(grasp);
  EXPECT_EQ(test.steps(), steps);
  EXPECT_EQ(a.held, b.held);
  EXPECT_DOUBLE_EQ(a.slip_m, b.slip_m);
  EXPECT_EQ(a.contacts.size(), b.contacts.size());
}

TEST(LiftTest, ContactsAllOnOneSideAreNotTheGraspTheHandTakes) {
  // The thumb cannot oppose fingers beside it: opened wide enough to pass the can, the hand closes
  // around the whole can, far from the planned contacts.
  LiftTest test(can(), {});
  const auto r = test.run(grasp_at_angles(test, 0, 35 * kDegree, -35 * kDegree));
  EXPECT_FALSE(r.held);
  EXPECT_NE(r.reason.find("not the planned grasp"), std::string::npos) << r.reason;
}

TEST(LiftTest, TwoFingersOnOneFaceOfABoxPushingTheSameWayDoNotHold) {
  // All three contacts on the box's +x face: the thumb and the fingers push the same way.
  const auto box = fba::geometry::make_box({-0.03, -0.05, 0}, {0.03, 0.05, 0.12});
  LiftTest test(box, {});
  fba::Grasp g;
  g.contacts[0].position = {0.03, 0, 0.06};
  g.contacts[1].position = {0.03, 0.03, 0.04};
  g.contacts[2].position = {0.03, -0.03, 0.04};
  for (auto& c : g.contacts) c.normal = {-1, 0, 0};
  g.approach = {0, 0, -1};
  g.aperture = 0.06;
  const auto r = test.run(g);
  EXPECT_FALSE(r.held);
  EXPECT_NE(r.reason.find("not apart across the approach"), std::string::npos) << r.reason;
}

TEST(LiftTest, FingersClosingAboveTheObjectFindNoContact) {
  LiftTest test(can(), {});
  auto grasp = fba::sim_hand::ring_grasp(test.object(), mid_height(test.object()), 0);
  for (auto& c : grasp.contacts) c.position.z() += 0.2;  // in the air above the can
  const auto r = test.run(grasp);
  EXPECT_FALSE(r.held);
  EXPECT_TRUE(r.contacts.empty());
  EXPECT_NE(r.reason.find("no contact"), std::string::npos) << r.reason;
}

TEST(LiftTest, ApproachFromUnderTheTableCollidesAtThePregrasp) {
  LiftTest test(can(), {});
  auto grasp = fba::sim_hand::ring_grasp(test.object(), mid_height(test.object()), 0);
  grasp.approach = Eigen::Vector3d::UnitZ();  // the palm would be under the table
  const auto r = test.run(grasp);
  EXPECT_FALSE(r.held);
  EXPECT_NE(r.reason.find("collision at the pregrasp, even with the hand fully open"), std::string::npos) << r.reason;
  EXPECT_NE(r.reason.find("table"), std::string::npos) << r.reason;
}

TEST(LiftTest, ContactsWiderThanTheHandAreOutOfReach) {
  const auto wide = fba::geometry::make_box({-0.2, -0.03, 0}, {0.2, 0.03, 0.1});
  LiftTest test(wide, {});
  fba::Grasp g;
  g.contacts[0].position = {-0.2, 0, 0.05};
  g.contacts[1].position = {0.2, 0.02, 0.05};
  g.contacts[2].position = {0.2, -0.02, 0.05};
  g.contacts[0].normal = {1, 0, 0};
  g.contacts[1].normal = g.contacts[2].normal = {-1, 0, 0};
  g.approach = {0, 0, -1};
  const auto r = test.run(g);
  EXPECT_FALSE(r.held);
  EXPECT_NE(r.reason.find("beyond the hand's opening"), std::string::npos) << r.reason;
}

TEST(LiftTest, TooLittleFrictionForTheWeightDrops) {
  LiftTestParams p;
  p.mass = 2.0;       // 19.6 N of weight
  p.friction = 0.05;  // against at most 0.05 * 40 N of friction
  LiftTest test(can(), {}, p);
  const auto r = test.run(fba::sim_hand::ring_grasp(test.object(), mid_height(test.object()), 180 * kDegree));
  EXPECT_FALSE(r.held);
  EXPECT_NE(r.reason.find("dropped at t="), std::string::npos) << r.reason;
}

TEST(LiftTest, NonFiniteGraspIsRefused) {
  LiftTest test(can(), {});
  fba::Grasp g = fba::sim_hand::ring_grasp(test.object(), mid_height(test.object()), 0);
  g.contacts[1].position.x() = NAN;
  EXPECT_THROW(test.run(g), std::invalid_argument);
  g = fba::sim_hand::ring_grasp(test.object(), mid_height(test.object()), 0);
  g.approach.setZero();
  EXPECT_THROW(test.run(g), std::invalid_argument);
}

// MuJoCo's STL reader takes at most 200,000 faces: a finer object is decimated for the physics,
// which says so with the counts, and the lift test runs on it.
TEST(LiftTest, AnObjectOverMuJoCosFaceLimitIsDecimatedForThePhysicsAndHeld) {
  fba::test::TempDir dir;
  const auto obj = dir.path() / "fine_sphere.obj";
  fba::test::write_obj(fba::geometry::make_uv_sphere({0, 0, 0.04}, 0.04, 400, 300), obj);
  const fba::TriangleMesh mesh = fba::geometry::load_mesh(obj);
  ASSERT_EQ(mesh.triangles.size(), 239200u);
  LiftTest test(mesh, {});
  EXPECT_EQ(test.object().triangles.size(), 239200u);  // contacts are computed on every triangle
  const std::string note = test.physics_note();
  EXPECT_EQ(note.rfind("the object's 239200 triangles were decimated to ", 0), 0u) << note;
  EXPECT_NE(note.find("for MuJoCo (at most 50000)"), std::string::npos) << note;
  const auto r = test.run(fba::sim_hand::ring_grasp(test.object(), mid_height(test.object()), 0));
  EXPECT_TRUE(r.held) << r.reason;
}

TEST(LiftTest, AnObjectWithinTheBoundIsGivenToMuJoCoAsItIs) { EXPECT_EQ(LiftTest(can(), {}).physics_note(), ""); }

TEST(LiftTest, EmptyMeshIsAClearError) {
  try {
    LiftTest test(fba::TriangleMesh{}, {});
    FAIL() << "no error";
  } catch (const LiftTestError& e) {
    EXPECT_NE(std::string(e.what()).find("no triangles"), std::string::npos) << e.what();
  }
}

TEST(LiftTest, HandModelThatDoesNotCompileGivesMuJoCosMessage) {
  try {
    LiftTest test(can(), {}, {}, "<mujoco><worldbody><geom type=\"nonsense\"/></worldbody></mujoco>");
    FAIL() << "no error";
  } catch (const LiftTestError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("MuJoCo does not compile the scene"), std::string::npos) << what;
    EXPECT_NE(what.find("nonsense"), std::string::npos) << what;  // MuJoCo's own text names the bad value
  }
}

TEST(LiftTest, HandModelWithoutTheHandsPartsSaysWhichIsMissing) {
  try {
    LiftTest test(can(), {}, {}, "<mujoco><worldbody><geom name=\"table\" type=\"plane\" size=\"1 1 0.1\"/></worldbody></mujoco>");
    FAIL() << "no error";
  } catch (const LiftTestError& e) {
    EXPECT_NE(std::string(e.what()).find("'palm'"), std::string::npos) << e.what();
  }
}

TEST(LiftTest, BuiltInHandModelIsTheModelFile) {
  std::ifstream in(fba::test::source_dir() + "/hardware/robots/three_finger_hand.xml");
  ASSERT_TRUE(in);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(LiftTest::hand_model(), text.str());
}

}  // namespace
