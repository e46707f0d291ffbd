// The robot's hand as grasp synthesis checks it against the table: its collision shapes (the palm
// and the fingers' links) posed in the world at each pose the hand takes for a grasp. Synthesis
// does not describe the hand itself: whoever runs it hands it the robot's one description (the
// grasp.synthesis component: reach planning's hand, fba::motion's hand_parts() and place_hand(),
// from which the lift test's MuJoCo world is generated too), so that a candidate synthesis keeps is
// one the planner does not refuse for the table.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "fba/types/grasp.hpp"

namespace fba::grasp {

// One collision shape in the world: a box (size: half sizes along its frame's axes) or a cylinder
// (along its frame's z, centred on its origin; size: radius, length, 0).
struct HandShape {
  enum class Kind { Box, Cylinder };
  std::string name;  // "palm", "thumb", ...: what a refusal names
  Kind kind = Kind::Box;
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
  Eigen::Isometry3d world_from_shape = Eigen::Isometry3d::Identity();
};

// The hand posed for a grasp, or why it cannot take it at all (contacts wider than it opens, its
// fingers' contacts farther apart than its spread).
struct PosedHand {
  std::vector<HandShape> shapes;  // every pose together: open at the pregrasp, open at the grasp, closed on the contacts
  std::string why;                // non-empty: the hand cannot take the grasp
};

struct RobotHand {
  // The hand's shapes for a grasp (its contacts, approach, aperture, spread and pinch_depth).
  std::function<PosedHand(const Grasp&)> pose;
  // How far beyond the pads a contact may lie towards the fingertips (metres): the deepest pinch
  // (Grasp::pinch_depth). 0: the hand takes no pinch.
  double pinch_depth = 0;
  // How far beyond its contact a fingertip reaches at the least (metres): a pinch's, its deepest
  // contact's distance from the tip. From above, a finger touching a point reaches that far below
  // it, so a point lower than the table's clearance by that is no contact, whatever the grasp
  // (the table check of each candidate's hand settles the rest). Unset: not used.
  std::optional<double> tip_beyond_contact;
  explicit operator bool() const { return static_cast<bool>(pose); }
};

// The lowest point of a shape, world z.
double lowest_z(const HandShape& shape);

}  // namespace fba::grasp
