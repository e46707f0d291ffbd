// Where the palm goes to take a grasp, by the convention of the lift test
// (hardware/hand/sim/lift_test.cpp): the palm frame's z along the approach, x from the thumb's
// contact to the fingers' midpoint across the approach; the pads at the contacts' mean depth along
// the approach (stood back by the grasp's pinch_depth for a fingertip pinch), centred between the
// thumb and the fingers across it and on the fingers' midpoint beside it.
#pragma once

#include <string>

#include <Eigen/Geometry>

#include "fba/types/grasp.hpp"

namespace fba::motion {

struct HandPlacement {
  Eigen::Isometry3d world_from_palm = Eigen::Isometry3d::Identity();  // at the grasp
  // The pregrasp's opening (pad to pads, inner surfaces): the grasp's aperture, and at least the
  // contacts' width plus a clearance on each side. m.
  double opening = 0;
  double width = 0;   // the contacts' distance across the approach: the opening at which the pads touch them, m
  double spread = 0;  // between the two fingers' axes, m
  std::string why;    // non-empty: the hand cannot take the grasp, and why
};

// `clearance`: metres between each pad and its contact at the pregrasp, at least.
HandPlacement place_hand(const Grasp& grasp, double clearance = 0.01);

}  // namespace fba::motion
