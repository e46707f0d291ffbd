// The robot as the components that move it read it: its URDF with the measured transforms in place
// (hardware/arm/robot_parameters.hpp). The arm publishes it, so that a live view draws the robot the
// components use.
#pragma once

#include <string>

#include "fba/data_type.hpp"
#include "fba/types/robot_types_views.hpp"

namespace fba {

struct RobotDescription {
  std::string urdf;  // the URDF's text
  std::string name;  // what to call it in messages: its file, and which origins parameters replaced
};

}  // namespace fba

FBA_DATA_TYPE(fba::RobotDescription, "fba.RobotDescription",
              "The robot's URDF text as the components read it, the measured origins (base_pose, flange_to_palm, "
              "flange_to_camera) in place, and its name.");
