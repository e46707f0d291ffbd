// The three-fingered hand on the robot's flange as collision shapes: the hand the robot's URDF
// describes (hardware/robots/wrist_camera_arm.urdf), from which the lift test's MuJoCo world is
// generated. Its dimensions are constants here for the planner's code; each is checked against the
// URDF's (hardware/hand/tests/hand_geometry_test.cpp), until reach planning takes the hand's shapes
// from the URDF as it takes the arm's.
//
// Palm frame (as the URDF and the lift test use it): z is the approach (the fingers point along
// +z), x runs from the thumb to the two fingers, y = z cross x. The thumb stands at -x and the two
// fingers at +x, finger_a on the +y side; each closes along x on a straight slide.
#pragma once

#include <array>
#include <string>

#include <Eigen/Geometry>

namespace fba::motion {

namespace hand {
// The palm: a box centred below the palm frame's origin.
inline constexpr double kPalmHalfWidth = 0.11;       // x, thumb to fingers
inline constexpr double kPalmHalfDepth = 0.065;      // y
inline constexpr double kPalmHalfThickness = 0.02;   // z
inline constexpr double kPalmCentreZ = -0.025;
// Each finger's knuckle (its slide's carriage) stands this far from the palm's centre along x
// when fully open, and this high along z.
inline constexpr double kKnuckleX = 0.12;
inline constexpr double kKnuckleZ = 0.03;
// The closing slide's travel from fully open.
inline constexpr double kTravel = 0.1;
// Each finger: three straight phalanges, base first, lengths and radii. The proximal and middle
// ones are capsules (capped by half spheres at their joints); the distal one, the fingertip, is a
// cylinder capped only at its joint, its end flat: its side touches a wall down to the end, where a
// rounded tip meets a wall no lower than its radius above the table, too high for a flat plate.
inline constexpr std::array<double, 3> kPhalanxLength{0.06, 0.045, 0.04};
inline constexpr std::array<double, 3> kPhalanxRadius{0.011, 0.011, 0.01};
// The pad: this far along the distal phalanx from its base.
inline constexpr double kPadAlongDistal = 0.015;
// The two fingers' axes stand this far apart at least and at most (the scissor's range).
inline constexpr double kSpreadMin = 0.02;
inline constexpr double kSpreadMax = 0.12;

// The knuckle to the fingertip's flat end.
inline constexpr double kFingerLength = kPhalanxLength[0] + kPhalanxLength[1] + kPhalanxLength[2];
// The pads' distance from the palm frame along z.
inline constexpr double kPadDistance = kKnuckleZ + kPhalanxLength[0] + kPhalanxLength[1] + kPadAlongDistal;
// The pad's radius: the distal phalanx's.
inline constexpr double kPadRadius = kPhalanxRadius[2];
// The deepest contact a pinch takes lies this far short of the fingertip's end: on the pad, not on
// the rim of its flat end.
inline constexpr double kPinchShortOfTip = 0.003;
// How far beyond the pads that deepest contact lies: the deepest pinch (Grasp::pinch_depth).
inline constexpr double kDeepestPinch = kPhalanxLength[2] - kPinchShortOfTip - kPadAlongDistal;
}  // namespace hand

// One collision shape of the hand, in the palm frame.
struct HandPart {
  enum class Kind { Box, Cylinder };
  std::string name;  // "palm", "thumb", "finger_a", "finger_b"
  Kind kind = Kind::Box;
  // Box: the half sizes; cylinder (along z, centred): radius, length, 0.
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
  Eigen::Isometry3d palm_from_part = Eigen::Isometry3d::Identity();
};

// The palm and the three fingers, straight, each finger one cylinder as thick as its thickest
// phalanx, from its proximal phalanx's cap at the knuckle to its flat tip. `opening`: the thumb's
// pad to the fingers' pads, inner surfaces, m (closed as far as the slides go when smaller);
// `spread`: between the two fingers' axes, m (within the scissor's range).
std::array<HandPart, 4> hand_parts(double opening, double spread);

// The slide travel that puts each pad's inner surface half_opening from the palm's centre along x,
// within [0, kTravel].
double travel_for(double half_opening);

}  // namespace fba::motion
