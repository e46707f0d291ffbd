// The angle between two directions, as the grasp library measures it everywhere (normals,
// opposition, a camera's move, a model normal's error on the true surface).
#pragma once

#include <cmath>
#include <numbers>

#include <Eigen/Core>

namespace fba::grasp {

// Radians in [0, pi]; 0 when either vector is zero. atan2 of the cross and dot products stays
// accurate for nearly parallel vectors, where acos of the dot product loses half its digits.
inline double angle_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// The same in degrees, for reports, messages and tests.
inline double angle_between_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return angle_between(a, b) * 180 / std::numbers::pi;
}

}  // namespace fba::grasp
