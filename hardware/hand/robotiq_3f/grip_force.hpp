// The Robotiq 3-Finger's grip force at each finger, as its manual gives it (section 4): hw.robotiq_3f
// maps its force register (0..255) over this range, and sim.hand's lift test closes its fingers with
// a force in it and holds a stopped finger within it.
#pragma once

#include <algorithm>

namespace fba::robotiq {

inline constexpr double kMinForce = 15.0;  // N, at register value 0
inline constexpr double kMaxForce = 60.0;  // N, at 255 (the relation taken as linear between)

// The force the gripper closes with when a close asks for `requested` newtons: the range's nearest.
inline constexpr double grip_force(double requested) { return std::clamp(requested, kMinForce, kMaxForce); }

}  // namespace fba::robotiq
