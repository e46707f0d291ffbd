// The arm's kinematics from the project's URDF: FK/IK round trips, limits, unreachable poses,
// clear errors for bad descriptions, and the joint-space trajectory's limits.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>

#include "arm_model.hpp"
#include "support/wrist_camera_arm.hpp"
#include "support/temp_dir.hpp"
#include "support/build_paths.hpp"

using fba::arm::ArmModel;
using fba::arm::ArmModelError;
using fba::arm::JointTrajectory;

namespace {

const std::string kUrdf = fba::test::wrist_camera_arm_urdf();

using fba::test::wrist_camera_arm;

Eigen::VectorXd home() {
  Eigen::VectorXd q(6);
  q << -0.4148, -2.1223, 2.2888, -2.2234, -1.3679, -0.3644;
  return q;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const ArmModelError& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST(ArmModel, TheProjectArmHasSixRevoluteJointsWithTheirLimits) {
  const std::vector<std::string> names{"shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                                       "wrist_1_joint",      "wrist_2_joint",       "wrist_3_joint"};
  EXPECT_EQ(wrist_camera_arm().joint_names(), names);
  for (const auto& l : wrist_camera_arm().limits()) {
    EXPECT_NEAR(l.lower, -M_PI, 1e-6);
    EXPECT_NEAR(l.upper, M_PI, 1e-6);
    EXPECT_GE(l.velocity, 3.15);
  }
}

// The camera's optical frame at the home joints: 0.35 m from the object's origin, looking at it.
TEST(ArmModel, HomeJointsPointTheCameraAtTheObject) {
  const Eigen::Isometry3d camera = wrist_camera_arm().forward(home());
  EXPECT_NEAR(camera.translation().norm(), 0.35, 0.005);
  const Eigen::Vector3d to_object = -camera.translation().normalized();
  EXPECT_GT(camera.linear().col(2).dot(to_object), std::cos(1.0 * M_PI / 180));  // z forward, within 1 degree
}

// The UR5's straight-up pose: every joint at zero but the lifts puts the flange at the summed link lengths.
TEST(ArmModel, ForwardKinematicsMatchesTheUr5Dimensions) {
  const ArmModel flange(kUrdf, "base_link", "flange");
  Eigen::VectorXd q = Eigen::VectorXd::Zero(6);
  q(1) = -M_PI / 2;  // shoulder lift: upper arm vertical
  q(3) = -M_PI / 2;  // wrist 1: back to vertical
  const Eigen::Vector3d p = flange.forward(q).translation();
  EXPECT_NEAR(p.z(), 0.089159 + 0.425 + 0.39225 + 0.09465, 1e-6);
  EXPECT_NEAR(p.y(), 0.13585 - 0.1197 + 0.093 + 0.0823, 1e-6);
  EXPECT_NEAR(p.x(), 0.0, 1e-6);
}

TEST(ArmModel, InverseOfForwardReachesTheSamePoseOverRandomReachableConfigurations) {
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> joint(-M_PI, M_PI);
  for (int i = 0; i < 60; ++i) {
    Eigen::VectorXd q(6);
    for (int j = 0; j < 6; ++j) q(j) = joint(random);
    const Eigen::Isometry3d pose = wrist_camera_arm().forward(q);
    const auto ik = wrist_camera_arm().inverse(pose, home());
    ASSERT_TRUE(ik.ok) << "configuration " << i << ": " << ik.why;
    EXPECT_EQ(wrist_camera_arm().limit_violation(ik.joints), "");
    const Eigen::Isometry3d reached = wrist_camera_arm().forward(ik.joints);
    EXPECT_LT((reached.translation() - pose.translation()).norm(), 1e-4) << i;
    EXPECT_LT(fba::arm::angle_between(reached, pose), 1e-3) << i;
  }
}

TEST(ArmModel, InverseFromTheCurrentJointsStaysThere) {
  const auto ik = wrist_camera_arm().inverse(wrist_camera_arm().forward(home()), home());
  ASSERT_TRUE(ik.ok) << ik.why;
  EXPECT_LT((ik.joints - home()).cwiseAbs().maxCoeff(), 1e-6);
}

TEST(ArmModel, JointsOutsideTheirLimitsAreNamed) {
  Eigen::VectorXd q = home();
  EXPECT_EQ(wrist_camera_arm().limit_violation(q), "");
  q(2) = 3.5;
  EXPECT_EQ(wrist_camera_arm().limit_violation(q), "joint 'elbow_joint' at 3.5 rad is outside [-3.14159, 3.14159]");
  q(2) = std::nan("");
  EXPECT_NE(wrist_camera_arm().limit_violation(q).find("elbow_joint"), std::string::npos);
  EXPECT_EQ(wrist_camera_arm().limit_violation(Eigen::VectorXd::Zero(5)), "5 joint positions given, the arm has 6");
}

TEST(ArmModel, APoseOutOfReachIsRefusedWithTheErrorOfTheBestAttempt) {
  Eigen::Isometry3d far = Eigen::Isometry3d::Identity();
  far.translation() << 2.0, 0.0, 0.5;  // 2.45 m from the base; the arm reaches about 0.95 m
  const auto ik = wrist_camera_arm().inverse(far, home());
  EXPECT_FALSE(ik.ok);
  EXPECT_GT(ik.position_error, 1.0);
  EXPECT_NE(ik.why.find("no joint positions reach it: the closest of 32 attempts is"), std::string::npos) << ik.why;
  EXPECT_NE(ik.why.find(" m and "), std::string::npos) << ik.why;
}

TEST(ArmModel, AURDFThatDoesNotParseSaysWhy) {
  const std::string e = error_of([] { ArmModel::from_string("<robot><link/></robot>", "bad.urdf", "a", "b"); });
  EXPECT_NE(e.find("URDF bad.urdf does not parse: "), std::string::npos) << e;
  EXPECT_NE(e.find("No name given for the robot"), std::string::npos) << e;
  const std::string not_xml = error_of([] { ArmModel::from_string("not xml at all", "text.urdf", "a", "b"); });
  EXPECT_NE(not_xml.find("URDF text.urdf does not parse: "), std::string::npos) << not_xml;
}

TEST(ArmModel, AFileThatIsMissingOrAFolderIsNamed) {
  fba::test::TempDir dir;
  EXPECT_EQ(error_of([&] { ArmModel(dir.path() / "none.urdf", "world", "camera"); }),
            "URDF " + (dir.path() / "none.urdf").string() + " does not exist");
  EXPECT_EQ(error_of([&] { ArmModel(dir.path(), "world", "camera"); }), "URDF " + dir.path().string() + " is not a regular file");
}

TEST(ArmModel, AMissingLinkIsNamedWithTheLinksThereAre) {
  const std::string e = error_of([] { ArmModel(kUrdf, "world", "gripper"); });
  EXPECT_EQ(e.rfind("no link 'gripper' in " + kUrdf + "; links: ", 0), 0u) << e;
  EXPECT_NE(e.find("camera"), std::string::npos) << e;
  EXPECT_NE(e.find("wrist_3_link"), std::string::npos) << e;
}

TEST(ArmModel, ARevoluteJointWithoutALimitIsRefusedNamingIt) {
  const std::string xml = R"(<robot name="r"><link name="a"/><link name="b"/>
      <joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/></joint></robot>)";
  const std::string e = error_of([&] { ArmModel::from_string(xml, "r.urdf", "a", "b"); });
  EXPECT_NE(e.find("r.urdf"), std::string::npos) << e;
  EXPECT_NE(e.find("Joint [j] is of type REVOLUTE but it does not specify limits"), std::string::npos) << e;
}

TEST(JointTrajectory, ALongMoveIsTrapezoidalAndAShortOneTriangular) {
  const Eigen::VectorXd v = Eigen::VectorXd::Constant(1, 1.0), a = Eigen::VectorXd::Constant(1, 2.0);
  // 2 rad at 1 rad/s, 2 rad/s^2: 0.5 s up, 1.5 s cruising, 0.5 s down.
  EXPECT_NEAR(JointTrajectory(Eigen::VectorXd::Zero(1), Eigen::VectorXd::Constant(1, 2.0), v, a).duration(), 2.5, 1e-12);
  // 0.1 rad never reaches full speed: 2 sqrt(d / a).
  EXPECT_NEAR(JointTrajectory(Eigen::VectorXd::Zero(1), Eigen::VectorXd::Constant(1, 0.1), v, a).duration(), 2 * std::sqrt(0.05),
              1e-12);
  EXPECT_EQ(JointTrajectory(Eigen::VectorXd::Ones(1), Eigen::VectorXd::Ones(1), v, a).duration(), 0.0);
}

TEST(JointTrajectory, EveryJointStaysWithinItsLimitsAndAllArriveTogetherAtTheGoal) {
  Eigen::VectorXd start(6), goal(6), vmax(6), amax(6);
  start << 0.0, -2.0, 1.9, -1.4, -1.5, 0.0;
  goal << 1.2, -1.0, 0.5, -2.4, -1.0, 2.5;
  vmax << 1.5, 1.5, 1.5, 1.6, 1.6, 0.4;
  amax << 3, 3, 3, 3, 3, 3;
  const JointTrajectory t(start, goal, vmax, amax);
  const double dt = 1e-3;
  Eigen::VectorXd q, v, q_prev, v_prev;
  t.sample(0, q_prev, v_prev);
  EXPECT_EQ(q_prev, start);
  EXPECT_EQ(v_prev.cwiseAbs().maxCoeff(), 0.0);
  bool some_joint_at_its_limit = false;
  for (double time = dt; time < t.duration() + 2 * dt; time += dt) {
    t.sample(time, q, v);
    for (int j = 0; j < 6; ++j) {
      EXPECT_LE(std::abs(v(j)), vmax(j) * (1 + 1e-9)) << "joint " << j << " at " << time;
      EXPECT_LE(std::abs(v(j) - v_prev(j)) / dt, amax(j) * (1 + 1e-6)) << "joint " << j << " at " << time;
      // Straight in joint space: every joint the same share of the way.
      EXPECT_NEAR((q(j) - start(j)) / (goal(j) - start(j)), (q(0) - start(0)) / (goal(0) - start(0)), 1e-9);
      some_joint_at_its_limit |= std::abs(v(j)) > vmax(j) * 0.999;
    }
    q_prev = q;
    v_prev = v;
  }
  EXPECT_TRUE(some_joint_at_its_limit);  // the slowest joint sets the pace: no time wasted
  t.sample(t.duration(), q, v);
  EXPECT_EQ(q, goal);
  EXPECT_EQ(v.cwiseAbs().maxCoeff(), 0.0);
}
