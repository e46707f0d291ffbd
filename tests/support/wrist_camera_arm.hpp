// The project's arm (hardware/robots/wrist_camera_arm.urdf) from its base to its camera, parsed
// once per test binary: the simulated arm's and the CANopen arm's tests move the same one.
#pragma once

#include <fstream>
#include <sstream>
#include <string>

#include "arm_model.hpp"
#include "support/build_paths.hpp"

namespace fba::test {

inline std::string wrist_camera_arm_urdf() { return source_dir() + "/hardware/robots/wrist_camera_arm.urdf"; }

// The file's text, as fba::arm::RobotParameters::read gives it when no transform is measured.
inline std::string wrist_camera_arm_text() {
  std::ifstream in(wrist_camera_arm_urdf(), std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

inline const arm::ArmModel& wrist_camera_arm() {
  static const arm::ArmModel model(wrist_camera_arm_urdf(), "world", "camera");
  return model;
}

}  // namespace fba::test
