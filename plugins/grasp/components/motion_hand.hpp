// The robot's hand for grasp synthesis's table check (fba::grasp::RobotHand), from reach planning's
// description of it (fba::motion: hand_parts(), whose dimensions are the URDF's, and place_hand(),
// the palm's placement the planner and the lift test use): the hand synthesis keeps off the table
// is the one the arm carries. Header-only: the plugin and its tests link fba::motion, the grasp
// library does not.
#pragma once

#include <vector>

#include "fba/grasp/robot_hand.hpp"
#include "fba/motion/hand_geometry.hpp"
#include "fba/motion/hand_placement.hpp"

namespace fba::grasp {

// `standoff`: metres back along the approach where the pregrasp is; `clearance`: between each pad
// and its contact there (fba::motion::ReachParams' standoff and clearance).
inline RobotHand motion_hand(double standoff, double clearance) {
  RobotHand hand;
  // A pinch puts the contacts on the distal phalanx up to a little short of its flat end.
  hand.pinch_depth = motion::hand::kDeepestPinch;
  hand.tip_beyond_contact = motion::hand::kPinchShortOfTip;
  hand.pose = [standoff, clearance](const Grasp& grasp) {
    PosedHand posed;
    const motion::HandPlacement place = motion::place_hand(grasp, clearance);
    if (!place.why.empty()) return posed.why = place.why, posed;
    const Eigen::Vector3d approach = place.world_from_palm.linear().col(2);
    const Eigen::Isometry3d& at_grasp = place.world_from_palm;  // a pinch's palm stood back by place_hand
    const Eigen::Isometry3d at_pregrasp = Eigen::Translation3d(-approach * standoff) * at_grasp;
    auto add = [&](const Eigen::Isometry3d& world_from_palm, double opening) {
      for (const motion::HandPart& part : motion::hand_parts(opening, place.spread))
        posed.shapes.push_back({part.name, part.kind == motion::HandPart::Kind::Box ? HandShape::Kind::Box : HandShape::Kind::Cylinder,
                                part.size, world_from_palm * part.palm_from_part});
    };
    add(at_pregrasp, place.opening);  // open, where the straight approach begins
    add(at_grasp, place.opening);     // open, at the contacts
    add(at_grasp, place.width);       // closed on them, for the lift
    return posed;
  };
  return hand;
}

}  // namespace fba::grasp
