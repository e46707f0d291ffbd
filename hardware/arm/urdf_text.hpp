// A URDF's text parsed by urdfdom, with urdfdom's own reasons when it does not parse. urdfdom says
// them through console_bridge's process-wide log handler, which this takes over for the call under
// one lock for every reader of a URDF in the process (the arm's kinematics, the physics world).
#pragma once

#include <string>

#include <urdf_parser/urdf_parser.h>

namespace fba::arm {

// The model, or null with `problem` saying why ("no robot in it" when urdfdom said nothing).
urdf::ModelInterfaceSharedPtr parse_urdf(const std::string& xml, std::string& problem);

}  // namespace fba::arm
