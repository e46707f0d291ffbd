// The robot's hand against the table (robot_hand.hpp).
#include "fba/grasp/robot_hand.hpp"

#include <cmath>

namespace fba::grasp {

double lowest_z(const HandShape& s) {
  const Eigen::Matrix3d r = s.world_from_shape.linear();
  const double z = s.world_from_shape.translation().z();
  if (s.kind == HandShape::Kind::Capsule) return z - std::abs(r(2, 2)) * s.size.y() / 2 - s.size.x();
  return z - std::abs(r(2, 0)) * s.size.x() - std::abs(r(2, 1)) * s.size.y() - std::abs(r(2, 2)) * s.size.z();
}

}  // namespace fba::grasp
