// The project's robot, described once (hardware/robots/wrist_camera_arm.urdf): the hand on the
// flange beside the camera, as KDL reads it; the arm's collision shapes without the hand's; and the
// measured transforms a profile puts in place of the URDF's own.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "arm_model.hpp"
#include "support/wrist_camera_arm.hpp"

using fba::arm::ArmModel;
using fba::arm::ArmModelError;

namespace {

std::string urdf_text() {
  std::ifstream in(fba::test::wrist_camera_arm_urdf());
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

Eigen::VectorXd joints(double a, double b, double c, double d, double e, double f) {
  Eigen::VectorXd q(6);
  q << a, b, c, d, e, f;
  return q;
}

}  // namespace

// The palm 7.5 cm out along the flange's axis, its frame turned as the flange's: the fingers point
// out of the flange, past the camera.
TEST(RobotDescription, ThePalmIsOnTheFlangeAlongItsAxis) {
  const ArmModel to_palm(fba::test::wrist_camera_arm_urdf(), "world", "palm");
  const ArmModel to_flange(fba::test::wrist_camera_arm_urdf(), "world", "flange");
  EXPECT_EQ(to_palm.joint_names(), to_flange.joint_names());  // the hand adds no joint to the arm's chain
  for (const auto& q : {joints(0, -1.57, 0, -1.57, 0, 0), joints(-0.41, -2.12, 2.29, -2.22, -1.37, -0.36)}) {
    const Eigen::Isometry3d flange_from_palm = to_flange.forward(q).inverse() * to_palm.forward(q);
    EXPECT_TRUE(flange_from_palm.linear().isIdentity(1e-12));
    EXPECT_TRUE(flange_from_palm.translation().isApprox(Eigen::Vector3d(0, 0, 0.075), 1e-12));
  }
}

// The hand's links are a mechanism of their own (slides and hinges): the arm's shapes are its seven
// links and the camera, as before the hand was described, and reach planning adds the hand's parts
// at their openings.
TEST(RobotDescription, TheHandsShapesAreNotTheArms) {
  const ArmModel arm(fba::test::wrist_camera_arm_urdf(), "world", "flange");
  ASSERT_EQ(arm.collision_shapes().size(), 8u);
  for (const auto& s : arm.collision_shapes()) EXPECT_NE(s.link, "palm");
  // From the palm on, the hand's own chains: the thumb's slide and three hinges.
  const ArmModel thumb(fba::test::wrist_camera_arm_urdf(), "palm", "thumb_pad");
  EXPECT_EQ(thumb.joint_names(), (std::vector<std::string>{"thumb_close", "thumb_1", "thumb_2", "thumb_3"}));
  EXPECT_NEAR(thumb.limits()[0].upper, 0.1, 1e-12);
  const Eigen::Isometry3d open = thumb.forward(Eigen::VectorXd::Zero(4));
  EXPECT_TRUE(open.translation().isApprox(Eigen::Vector3d(-0.12, 0, 0.03 + 0.06 + 0.045 + 0.015), 1e-12));
  const ArmModel finger(fba::test::wrist_camera_arm_urdf(), "palm", "finger_a_pad");
  EXPECT_EQ(finger.joint_names(),
            (std::vector<std::string>{"finger_a_spread", "finger_a_close", "finger_a_1", "finger_a_2", "finger_a_3"}));
  EXPECT_NEAR(finger.limits()[0].lower, 0.01, 1e-12);
  EXPECT_NEAR(finger.limits()[0].upper, 0.06, 1e-12);
}

// The measured transforms (the robot's parameters) replace the URDF's: the palm and the camera on
// the flange, the base on the table. Only fixed joints take one, and a wrong name is refused with
// those there are.
TEST(RobotDescription, MeasuredTransformsReplaceTheUrdfsOrigins) {
  const Eigen::Isometry3d palm = fba::arm::pose_from_xyz_rpy({0.001, -0.002, 0.08, 0, 0, M_PI / 2}, "flange_to_palm");
  const Eigen::Isometry3d base = fba::arm::pose_from_xyz_rpy({-0.5, 0.1, 0.02, 0, 0, 0.3}, "base_pose");
  const std::string measured = fba::arm::with_fixed_joint_origins(urdf_text(), {{"flange_to_palm", palm}, {"world_to_base", base}});
  const ArmModel to_palm = ArmModel::from_string(measured, "measured", "world", "palm");
  const ArmModel to_flange = ArmModel::from_string(measured, "measured", "world", "flange");
  const Eigen::VectorXd q = joints(0.3, -1.2, 1.4, -1.8, -1.5, 0.2);
  EXPECT_TRUE((to_flange.forward(q).inverse() * to_palm.forward(q)).isApprox(palm, 1e-12));
  EXPECT_TRUE(to_flange.link_poses(q).front().isApprox(base, 1e-12));  // the base link's pose in the world
  // The rest of the robot is as it was: the camera on the flange.
  const ArmModel camera = ArmModel::from_string(measured, "measured", "world", "camera");
  EXPECT_TRUE((to_flange.forward(q).inverse() * camera.forward(q)).translation().isApprox(Eigen::Vector3d(0, 0.06, 0.03), 1e-12));
  try {
    fba::arm::with_fixed_joint_origins(urdf_text(), {{"flange_to_hand", palm}});
    FAIL() << "no error";
  } catch (const ArmModelError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("joint 'flange_to_hand'"), std::string::npos) << what;
    EXPECT_NE(what.find("world_to_base, wrist_3_to_flange, flange_to_camera, flange_to_palm"), std::string::npos) << what;
  }
  EXPECT_THROW(fba::arm::with_fixed_joint_origins(urdf_text(), {{"elbow_joint", palm}}), ArmModelError);
  EXPECT_THROW(fba::arm::pose_from_xyz_rpy({0, 0, 0}, "flange_to_palm"), std::invalid_argument);
}
