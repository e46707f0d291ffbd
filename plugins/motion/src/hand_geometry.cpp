#include "fba/motion/hand_geometry.hpp"

#include <algorithm>

namespace fba::motion {

double travel_for(double half_opening) {
  return std::clamp(hand::kKnuckleX - hand::kPadRadius - half_opening, 0.0, hand::kTravel);
}

std::array<HandPart, 4> hand_parts(double opening, double spread) {
  using namespace hand;
  const double travel = travel_for(opening / 2);
  const double half_spread = std::clamp(spread, kSpreadMin, kSpreadMax) / 2;
  const double radius = *std::max_element(kPhalanxRadius.begin(), kPhalanxRadius.end());
  auto at = [](double x, double y, double z) {
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.translation() << x, y, z;
    return t;
  };
  const double length = radius + kFingerLength;
  const double finger_z = kKnuckleZ - radius + length / 2;
  const Eigen::Vector3d cylinder(radius, length, 0);
  return {{
      {"palm", HandPart::Kind::Box, {kPalmHalfWidth, kPalmHalfDepth, kPalmHalfThickness}, at(0, 0, kPalmCentreZ)},
      {"thumb", HandPart::Kind::Cylinder, cylinder, at(-kKnuckleX + travel, 0, finger_z)},
      {"finger_a", HandPart::Kind::Cylinder, cylinder, at(kKnuckleX - travel, half_spread, finger_z)},
      {"finger_b", HandPart::Kind::Cylinder, cylinder, at(kKnuckleX - travel, -half_spread, finger_z)},
  }};
}

}  // namespace fba::motion
