// The robot's hand against the table (robot_hand.hpp).
#include "fba/grasp/robot_hand.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace fba::grasp {

double lowest_z(const HandShape& s) {
  const Eigen::Matrix3d r = s.world_from_shape.linear();
  const double z = s.world_from_shape.translation().z();
  if (s.kind == HandShape::Kind::Capsule) return z - std::abs(r(2, 2)) * s.size.y() / 2 - s.size.x();
  return z - std::abs(r(2, 0)) * s.size.x() - std::abs(r(2, 1)) * s.size.y() - std::abs(r(2, 2)) * s.size.z();
}

std::optional<std::string> hand_table_refusal(const Grasp& grasp, const RobotHand& hand, double table_z, double clearance) {
  if (!hand) throw std::invalid_argument("hand_table_refusal: the robot hand has no pose function");
  const PosedHand posed = hand.pose(grasp);
  if (!posed.why.empty()) return posed.why;
  for (const HandShape& s : posed.shapes)
    if (const double low = lowest_z(s); low < table_z + clearance) {
      char text[160];
      std::snprintf(text, sizeof text, "the %s reaches %.1f mm above the table, under the clearance of %.1f mm", s.name.c_str(),
                    (low - table_z) * 1e3, clearance * 1e3);
      return std::string(text);
    }
  return std::nullopt;
}

}  // namespace fba::grasp
