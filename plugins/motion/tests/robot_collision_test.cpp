// What collision checking reads from the arm's URDF (ArmModel's link poses and shapes), and what
// it finds: the table, the arm itself, the carved model, and the contacts' allowance.
#include <gtest/gtest.h>

#include <algorithm>

#include "arm_model.hpp"
#include "fba/motion/hand_placement.hpp"
#include "fba/motion/robot_collision.hpp"
#include "support/reach_scenes.hpp"

using namespace fba::motion;
using fba::arm::ArmModel;
using fba::arm::CollisionShape;

namespace {

const ArmModel& flange_arm() {
  static const ArmModel arm(test::arm_urdf(), "world", "flange");
  return arm;
}

const CollisionShape& shape_of(const std::string& link) {
  const auto& shapes = flange_arm().collision_shapes();
  const auto it = std::find_if(shapes.begin(), shapes.end(), [&](const CollisionShape& s) { return s.link == link; });
  EXPECT_NE(it, shapes.end()) << link;
  return *it;
}

}  // namespace

TEST(ArmModel, EachLinksPoseEndsAtTheForwardKinematics) {
  const std::vector<std::string> links{"base_link",    "shoulder_link", "upper_arm_link", "forearm_link",
                                       "wrist_1_link", "wrist_2_link",  "wrist_3_link",   "flange"};
  EXPECT_EQ(flange_arm().link_names(), links);
  const auto poses = flange_arm().link_poses(test::home());
  ASSERT_EQ(poses.size(), links.size());
  EXPECT_TRUE(poses.back().isApprox(flange_arm().forward(test::home()), 1e-12));
  EXPECT_TRUE(poses.front().translation().isApprox(Eigen::Vector3d(-0.45, 0, 0)));  // the base, bolted to the table
}

TEST(ArmModel, CollisionShapesAreTheUrdfsWithTheCameraMovingWithTheFlange) {
  EXPECT_EQ(flange_arm().collision_shapes().size(), 8u);  // seven links and the camera
  const CollisionShape& upper = shape_of("upper_arm_link");
  EXPECT_EQ(upper.kind, CollisionShape::Kind::Cylinder);
  EXPECT_TRUE(upper.size.isApprox(Eigen::Vector3d(0.054, 0.425, 0)));
  EXPECT_TRUE(upper.frame_from_shape.translation().isApprox(Eigen::Vector3d(0, 0, 0.2125)));
  EXPECT_EQ(upper.joints_before, 2u);
  const CollisionShape& camera = shape_of("camera");
  EXPECT_EQ(camera.kind, CollisionShape::Kind::Box);
  EXPECT_EQ(flange_arm().link_names()[camera.frame], "flange");
  EXPECT_EQ(camera.joints_before, 6u);
  EXPECT_TRUE(camera.frame_from_shape.translation().isApprox(Eigen::Vector3d(0, 0.06, 0.015)));
  EXPECT_EQ(shape_of("base_link").joints_before, 0u);
}

TEST(ArmModel, InverseKinematicsReturnsTheNearestSolutionTheCallerAccepts) {
  const Eigen::Isometry3d target = flange_arm().forward(test::home());
  fba::arm::IkOptions refuse_all;
  refuse_all.accept = [](const Eigen::VectorXd&) { return std::string("it is Tuesday"); };
  const auto none = flange_arm().inverse(target, test::home(), refuse_all);
  EXPECT_FALSE(none.ok);
  EXPECT_EQ(none.why, "every solution found is refused: it is Tuesday");
  EXPECT_EQ(none.attempts, 32);
  // Refusing the seed's own solution gives another one, away from it.
  fba::arm::IkOptions elsewhere;
  elsewhere.accept = [](const Eigen::VectorXd& q) {
    return (q - test::home()).norm() < 0.1 ? std::string("the current joints") : std::string();
  };
  const auto other = flange_arm().inverse(target, test::home(), elsewhere);
  ASSERT_TRUE(other.ok) << other.why;
  EXPECT_GE((other.joints - test::home()).norm(), 0.1);
  EXPECT_TRUE(flange_arm().forward(other.joints).isApprox(target, 1e-3));
}

TEST(RobotCollision, TheHomePoseBesideABoxTouchesNothing) {
  RobotCollision robot(flange_arm(), ReachParams{}.flange_from_palm);
  robot.set_model(std::make_shared<ModelObstacles>(test::box_model({0.06, 0.06, 0.10})));
  EXPECT_EQ(robot.collision(test::home()), "");
}

TEST(RobotCollision, ALinkBelowTheTableIsNamed) {
  RobotCollision robot(flange_arm(), ReachParams{}.flange_from_palm);
  Eigen::VectorXd q = test::home();
  q(1) = M_PI / 2;  // the upper arm straight down from the shoulder, 9 cm above the table
  EXPECT_EQ(robot.collision(q), "upper_arm_link touches the table");
}

TEST(RobotCollision, TheArmFoldedOntoItselfIsNamed) {
  RobotCollision robot(flange_arm(), ReachParams{}.flange_from_palm);
  Eigen::VectorXd q = test::home();
  q(1) = -M_PI / 2;  // the upper arm straight up
  q(2) = 3.0;        // the forearm folded down along it, onto the shoulder
  q(3) = 0;
  EXPECT_EQ(robot.collision(q), "forearm_link touches shoulder_link");
}

// The model bulges out round each contact, as a carved model does where the views' cones meet: the
// open hand coming down to the grasp meets the bulges, where its fingers are about to touch the
// object, and nothing else.
TEST(RobotCollision, TheModelIsAnObstacleSaveWhereTheFingersAreAboutToTouchTheObject) {
  const Eigen::Vector3d size(0.06, 0.06, 0.10);
  const fba::Grasp g = test::box_grasp(size, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.07);
  const auto box = fba::grasp::test::box_sdf(Eigen::Vector3d(0, 0, size.z() / 2), size);
  const auto bulges = [&](const Eigen::Vector3d& p) {
    double d = box(p);
    for (const auto& c : g.contacts) d = std::min(d, (p - c.position).norm() - 0.015);
    return d;
  };
  const auto model = std::make_shared<ModelObstacles>(fba::grasp::test::voxelise(bulges, test::workspace(), 6));
  const HandPlacement p = place_hand(g, 0.01);
  RobotCollision robot(flange_arm(), ReachParams{}.flange_from_palm);
  robot.set_hand(p.opening, p.spread);
  robot.set_model(model);
  const std::string c = robot.hand_collision(p.world_from_palm);
  EXPECT_EQ(c.rfind("thumb touches the model at (", 0), 0u) << c;
  const std::array<Eigen::Vector3d, 3> contacts{g.contacts[0].position, g.contacts[1].position, g.contacts[2].position};
  robot.set_model(model, contacts, 0.02);
  EXPECT_EQ(robot.hand_collision(p.world_from_palm), "");
  // The palm gets no allowance: lowered onto the box's top, it touches the model (the fingers
  // beside the box reach into the table then, but the palm is checked first).
  const Eigen::Isometry3d on_top = Eigen::Translation3d(0, 0, -0.13) * p.world_from_palm;
  EXPECT_EQ(robot.hand_collision(on_top).rfind("palm touches the model at (", 0), 0u) << robot.hand_collision(on_top);
  robot.check_model(false);
  EXPECT_EQ(robot.hand_collision(on_top), "thumb touches the table");
}

// The arm stands in a corner of the model (space no view carved): there is nothing of the object
// there. free_model_at frees the boxes the arm's links touch where it stands, and no other: the box
// where the upper arm would be with the arm turned stays an obstacle.
TEST(RobotCollision, WhereTheArmStandsTheModelIsFree) {
  const Eigen::VectorXd q = test::home();
  Eigen::VectorXd turned = q;
  turned(0) += 0.6;  // the shoulder turned: the upper arm elsewhere
  const Eigen::Vector3d here = flange_arm().link_poses(q)[2] * Eigen::Vector3d(0, 0, 0.2125);  // the upper arm's middle
  const Eigen::Vector3d there = flange_arm().link_poses(turned)[2] * Eigen::Vector3d(0, 0, 0.2125);
  auto cube = [](const Eigen::Vector3d& c) { return fba::grasp::test::box_sdf(c, Eigen::Vector3d::Constant(0.04)); };
  const auto two = [&](const Eigen::Vector3d& p) { return std::min(cube(here)(p), cube(there)(p)); };
  const Eigen::AlignedBox3d room(Eigen::Vector3d(-0.8, -0.8, -0.02), Eigen::Vector3d(0.8, 0.8, 1.58));  // a cube: the octree's root
  const auto model = std::make_shared<ModelObstacles>(fba::grasp::test::voxelise(two, room, 6));
  RobotCollision robot(flange_arm(), ReachParams{}.flange_from_palm);
  robot.set_model(model);
  EXPECT_EQ(robot.collision(q).rfind("upper_arm_link touches the model at (", 0), 0u) << robot.collision(q);
  robot.free_model_at(q);
  EXPECT_EQ(robot.collision(q), "");
  EXPECT_EQ(robot.collision(turned).rfind("upper_arm_link touches the model at (", 0), 0u) << robot.collision(turned);
  robot.set_model(model);  // a new model: nothing freed
  EXPECT_EQ(robot.collision(q).rfind("upper_arm_link touches the model at (", 0), 0u) << robot.collision(q);
}
