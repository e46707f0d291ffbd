// The project's arm (hardware/robots/wrist_camera_arm.urdf) from its base to its camera, parsed
// once per test binary: the simulated arm's and the CANopen arm's tests move the same one.
#pragma once

#include <string>

#include "arm_model.hpp"
#include "support/build_paths.hpp"

namespace fba::test {

inline std::string wrist_camera_arm_urdf() { return source_dir() + "/hardware/robots/wrist_camera_arm.urdf"; }

inline const arm::ArmModel& wrist_camera_arm() {
  static const arm::ArmModel model(wrist_camera_arm_urdf(), "world", "camera");
  return model;
}

}  // namespace fba::test
