// The robot's parameters (robot_parameters.hpp): the measured transforms, given as parameters,
// replace the URDF's fixed joints' origins for the arm, whose published camera pose follows them;
// a malformed value is a clear error naming the parameter.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include <fba/spec.hpp>
#include <fba/task_config.hpp>
#include <fba/testing.hpp>
#include <fba/types/joint_state.hpp>
#include <fba/types/pose.hpp>

#include "arm_model.hpp"
#include "robot_parameters.hpp"
#include "support/built_plugins.hpp"
#include "support/temp_dir.hpp"
#include "support/wrist_camera_arm.hpp"

using fba::arm::RobotParameters;
using fba::testing::ComponentHarness;

namespace {

// The URDF's own origins of the measured joints (hardware/robots/wrist_camera_arm.urdf).
const std::vector<double> kUrdfCamera{0, 0.06, 0.03, 0, 0, 0};
const std::vector<double> kUrdfBase{-0.45, 0, 0, 0, 0, 0};

// sim.arm with `params`, at its first tick: the joints and the camera pose where it starts.
std::pair<fba::JointState, fba::Pose> first_state(const fba::testing::Params& params) {
  ComponentHarness h(fba::test::built_plugins(), "sim.arm", params);
  h.tick();
  h.run();
  const auto states = h.values<fba::JointState>("joint_state");
  const auto poses = h.values<fba::Pose>("camera_pose");
  if (states.size() != 1 || poses.size() != 1) throw std::runtime_error("sim.arm did not publish where it starts: " + h.failure());
  return {states[0], poses[0]};
}

// RobotParameters::read on these values (the others their defaults).
fba::arm::RobotDescription read_robot(const std::map<std::string, fba::Value>& given) {
  fba::Spec spec = fba::Spec::filter("test.robot", "reads the robot");
  RobotParameters::add(spec);
  std::map<std::string, fba::Value> values;
  for (const auto& p : spec.params()) values[p.name] = given.count(p.name) ? given.at(p.name) : *p.default_value;
  return RobotParameters::read(fba::ParamValues(spec, values, "robot_parameters_test"));
}

}  // namespace

// Hand-eye calibration set on the arm: for the same joints, the camera pose it publishes is the
// flange's pose with the measured camera on it, not the URDF's.
TEST(RobotParameters, AFlangeToCameraSetThroughTheParameterMovesTheCameraPoseTheArmPublishes) {
  const std::vector<double> measured{0.012, 0.055, 0.041, 0.02, -0.03, 0.1};
  const auto [joints, camera] = first_state({});
  const auto [joints_measured, camera_measured] = first_state({{"flange_to_camera", measured}});
  EXPECT_EQ(joints_measured.positions, joints.positions);
  // world_from_camera' = world_from_flange * flange_from_camera' = world_from_camera * (urdf's)^-1 * measured
  const Eigen::Isometry3d expected = camera.world_from_frame * fba::arm::pose_from_xyz_rpy(kUrdfCamera, "urdf").inverse() *
                                     fba::arm::pose_from_xyz_rpy(measured, "measured");
  EXPECT_LT((camera_measured.world_from_frame.translation() - expected.translation()).norm(), 1e-9);
  EXPECT_LT(fba::arm::angle_between(camera_measured.world_from_frame, expected), 1e-9);
  EXPECT_GT((camera_measured.world_from_frame.translation() - camera.world_from_frame.translation()).norm(), 0.01);

  // The URDF's own values, given as measured, change nothing.
  const auto [joints_same, camera_same] = first_state({{"flange_to_camera", kUrdfCamera}});
  EXPECT_LT((camera_same.world_from_frame.translation() - camera.world_from_frame.translation()).norm(), 1e-12);
}

// The arm's base measured elsewhere on the table moves the whole arm, the camera with it.
TEST(RobotParameters, ABasePoseSetThroughTheParameterMovesTheArmOnTheTable) {
  const std::vector<double> measured{-0.43, 0.02, 0.001, 0, 0, 0.05};
  const auto [joints, camera] = first_state({});
  const auto [joints_measured, camera_measured] = first_state({{"base_pose", measured}});
  EXPECT_EQ(joints_measured.positions, joints.positions);
  const Eigen::Isometry3d expected = fba::arm::pose_from_xyz_rpy(measured, "measured") *
                                     fba::arm::pose_from_xyz_rpy(kUrdfBase, "urdf").inverse() * camera.world_from_frame;
  EXPECT_LT((camera_measured.world_from_frame.translation() - expected.translation()).norm(), 1e-9);
  EXPECT_LT(fba::arm::angle_between(camera_measured.world_from_frame, expected), 1e-9);
}

// Five numbers: the task does not load, and the message names the parameter and what it needs.
TEST(RobotParameters, AMalformedTransformIsAClearErrorNamingTheParameter) {
  for (const char* param : {"flange_to_camera", "flange_to_palm", "base_pose"}) {
    try {
      ComponentHarness h(fba::test::built_plugins(), "sim.arm", {{param, std::vector<double>{0, 0.06, 0.03, 0, 0}}});
      ADD_FAILURE() << param << ": accepted";
    } catch (const fba::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("parameter '" + std::string(param) + "' must have 0 or 6 numbers; found 5"), std::string::npos)
          << e.what();
    }
  }
  // Read directly (past the loader's check): a value that is not a number is refused too.
  try {
    read_robot({{"urdf", fba::test::wrist_camera_arm_urdf()}, {"flange_to_camera", std::vector<double>{0, 0.06, NAN, 0, 0, 0}}});
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "parameter 'flange_to_camera': every value must be finite");
  }
}

// Nothing measured: the file's text as it is, named by its path. Measured: the named joint's origin
// replaced, and the name says which parameters replaced origins.
TEST(RobotParameters, ReadGivesTheUrdfWithTheMeasuredOriginsInPlace) {
  const std::string file = fba::test::wrist_camera_arm_urdf();
  const auto plain = read_robot({{"urdf", file}});
  EXPECT_EQ(plain.urdf, fba::test::wrist_camera_arm_text());
  EXPECT_EQ(plain.name, file);

  const std::vector<double> palm{0.001, -0.002, 0.08, 0, 0, 0.3};
  const auto measured = read_robot({{"urdf", file}, {"flange_to_palm", palm}});
  EXPECT_EQ(measured.name, file + " (with the parameters flange_to_palm)");
  const auto to_flange = fba::arm::ArmModel::from_string(measured.urdf, measured.name, "world", "flange");
  const auto to_palm = fba::arm::ArmModel::from_string(measured.urdf, measured.name, "world", "palm");
  const Eigen::VectorXd q = Eigen::VectorXd::Constant(6, 0.3);
  const Eigen::Isometry3d flange_from_palm = to_flange.forward(q).inverse() * to_palm.forward(q);
  const Eigen::Isometry3d expected = fba::arm::pose_from_xyz_rpy(palm, "palm");
  EXPECT_LT((flange_from_palm.translation() - expected.translation()).norm(), 1e-12);
  EXPECT_LT(fba::arm::angle_between(flange_from_palm, expected), 1e-12);
}

// A measured transform for a URDF without that joint, or a file that is not there: the error says
// which parameter and which file.
TEST(RobotParameters, AMeasuredJointTheUrdfLacksOrAMissingFileIsAClearError) {
  const fba::test::TempDir dir;
  const std::string text = fba::test::wrist_camera_arm_text();
  std::string without_camera = text;
  const std::string joint = "<joint name=\"flange_to_camera\"";
  ASSERT_NE(without_camera.find(joint), std::string::npos);
  without_camera.replace(without_camera.find(joint), joint.size(), "<joint name=\"flange_to_eye\"");
  const std::string file = dir.write("other.urdf", without_camera).string();
  try {
    read_robot({{"urdf", file}, {"flange_to_camera", kUrdfCamera}});
    ADD_FAILURE() << "accepted";
  } catch (const fba::arm::ArmModelError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("parameter(s) flange_to_camera: cannot set the origin of joint 'flange_to_camera' in " + file + ": ", 0), 0u) << what;
    EXPECT_NE(what.find("flange_to_eye"), std::string::npos) << what;  // the fixed joints it has
  }
  const std::string missing = (dir.path() / "missing.urdf").string();
  try {
    read_robot({{"urdf", missing}});
    ADD_FAILURE() << "accepted";
  } catch (const fba::arm::ArmModelError& e) {
    EXPECT_EQ(std::string(e.what()), "parameter 'urdf': " + missing + " does not exist");
  }
}
