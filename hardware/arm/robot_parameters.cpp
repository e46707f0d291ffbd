#include "robot_parameters.hpp"

#include <dlfcn.h>

#include <fstream>
#include <map>
#include <sstream>
#include <utility>

namespace fba::arm {

// FBA_ROBOTS_FROM_PLUGIN: the robots' folder relative to the plugins' (hardware/arm/CMakeLists.txt).
// Linked into each plugin that reads the robot, with hidden symbols: dladdr names that plugin.
std::filesystem::path default_urdf() {
  Dl_info info{};
  if (!dladdr(reinterpret_cast<void*>(&default_urdf), &info) || !info.dli_fname) return "wrist_camera_arm.urdf";
  return (std::filesystem::path(info.dli_fname).parent_path() / FBA_ROBOTS_FROM_PLUGIN / "wrist_camera_arm.urdf").lexically_normal();
}

RobotDescription RobotParameters::read(const fba::ParamValues& params) {
  const std::filesystem::path given = params(kUrdf);
  const std::filesystem::path file = given.empty() ? default_urdf() : given;
  const std::string what = given.empty() ? "the robot's URDF" : "parameter 'urdf'";
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec))
    throw ArmModelError(what + ": " + file.string() + (std::filesystem::exists(file, ec) ? " is not a regular file" : " does not exist"));
  std::ifstream in(file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in) throw ArmModelError(what + ": cannot read " + file.string());

  std::map<std::string, Eigen::Isometry3d> origins;
  std::string measured;
  const std::pair<const char*, const fba::Param<std::vector<double>>*> measurable[] = {
      {kBaseJoint, &kBasePose}, {kPalmJoint, &kFlangeToPalm}, {kCameraJoint, &kFlangeToCamera}};
  for (const auto& [joint, param] : measurable) {
    const std::vector<double> v = params(*param);
    if (v.empty()) continue;
    const std::string name(param->name);
    origins[joint] = pose_from_xyz_rpy(v, "parameter '" + name + "'");
    measured += (measured.empty() ? "" : ", ") + name;
  }
  RobotDescription robot;
  robot.name = file.string();
  try {
    robot.urdf = with_fixed_joint_origins(text.str(), origins, robot.name);
  } catch (const ArmModelError& e) {
    throw ArmModelError("parameter(s) " + measured + ": " + e.what());
  }
  if (!measured.empty()) robot.name += " (with the parameters " + measured + ")";
  return robot;
}

}  // namespace fba::arm
