#include "fba/motion/hand_placement.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "fba/motion/hand_geometry.hpp"
#include "text.hpp"

namespace fba::motion {

using text::metres;

HandPlacement place_hand(const Grasp& grasp, double clearance) {
  HandPlacement p;
  for (const auto& c : grasp.contacts)
    if (!c.position.allFinite()) return p.why = "a contact's position is not finite", p;
  if (!grasp.approach.allFinite() || grasp.approach.norm() < 1e-9) return p.why = "the approach direction is zero or not finite", p;

  const Eigen::Vector3d a = grasp.approach.normalized();
  const Eigen::Vector3d thumb = grasp.contacts[0].position;
  const Eigen::Vector3d mid = (grasp.contacts[1].position + grasp.contacts[2].position) / 2;
  Eigen::Vector3d u = (mid - thumb) - a * a.dot(mid - thumb);
  p.width = u.norm();
  if (p.width < 1e-4) return p.why = "the thumb and the fingers' contacts are not apart across the approach", p;
  u /= p.width;
  const Eigen::Vector3d y = a.cross(u);
  const double spread = std::abs((grasp.contacts[1].position - grasp.contacts[2].position).dot(y));
  if (spread > hand::kSpreadMax + 1e-9)
    return p.why = "the fingers' contacts are " + metres(spread) + " apart, beyond the hand's spread of " + metres(hand::kSpreadMax), p;
  p.spread = std::max(spread, hand::kSpreadMin);
  const double widest = 2 * (hand::kKnuckleX - hand::kPadRadius);
  if (p.width > widest)
    return p.why = "the contacts are " + metres(p.width) + " apart across the approach, beyond the hand's opening of " + metres(widest), p;
  p.opening = std::min(std::max(std::isfinite(grasp.aperture) ? grasp.aperture : 0.0, p.width + 2 * clearance), widest);

  double along = 0;
  for (const auto& c : grasp.contacts) along += c.position.dot(a) / 3;
  const Eigen::Vector3d centre = u * (thumb.dot(u) + mid.dot(u)) / 2 + y * mid.dot(y) + a * along;
  p.world_from_palm.linear() << u, y, a;
  // The pads at the contacts' depth; a pinch (pinch_depth > 0) stands the palm back so that the
  // contacts lie that far along the distal phalanxes, towards their ends.
  const double pinch = std::isfinite(grasp.pinch_depth) ? std::max(grasp.pinch_depth, 0.0) : 0.0;
  p.world_from_palm.translation() = centre - a * (hand::kPadDistance + pinch);
  return p;
}

}  // namespace fba::motion
