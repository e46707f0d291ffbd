// The robot's hand against the table (robot_hand.hpp).
#include "fba/grasp/robot_hand.hpp"

#include <algorithm>
#include <cmath>

namespace fba::grasp {

double lowest_z(const HandShape& s) {
  const Eigen::Matrix3d r = s.world_from_shape.linear();
  const double z = s.world_from_shape.translation().z();
  // A cylinder's lowest point is on its rim: half its length down its axis, its radius across it.
  if (s.kind == HandShape::Kind::Cylinder)
    return z - std::abs(r(2, 2)) * s.size.y() / 2 - s.size.x() * std::sqrt(std::max(0.0, 1 - r(2, 2) * r(2, 2)));
  return z - std::abs(r(2, 0)) * s.size.x() - std::abs(r(2, 1)) * s.size.y() - std::abs(r(2, 2)) * s.size.z();
}

}  // namespace fba::grasp
