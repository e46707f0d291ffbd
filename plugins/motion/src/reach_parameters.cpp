#include "fba/motion/reach_parameters.hpp"

#include <algorithm>
#include <cmath>

namespace fba::motion {

std::optional<Eigen::VectorXd> arm_joints(const arm::ArmModel& arm, const fba::JointState& state, std::string& why) {
  const auto& names = arm.joint_names();
  Eigen::VectorXd q(static_cast<Eigen::Index>(names.size()));
  if (state.names.empty()) {
    if (state.positions.size() != names.size()) {
      why = "the joint state has " + std::to_string(state.positions.size()) + " positions without names; the arm has " +
            std::to_string(names.size()) + " joints";
      return std::nullopt;
    }
    for (std::size_t i = 0; i < names.size(); ++i) q(static_cast<Eigen::Index>(i)) = state.positions[i];
    return q;
  }
  for (std::size_t i = 0; i < names.size(); ++i) {
    std::size_t k = 0;
    while (k < state.names.size() && state.names[k] != names[i]) ++k;
    if (k == state.names.size() || k >= state.positions.size()) {
      why = "the joint state has no position for joint '" + names[i] + "'";
      return std::nullopt;
    }
    q(static_cast<Eigen::Index>(i)) = state.positions[k];
  }
  return q;
}

bool at_rest(const fba::JointState& state) {
  return std::all_of(state.velocities.begin(), state.velocities.end(), [](double v) { return std::abs(v) < 1e-3; });
}

}  // namespace fba::motion
