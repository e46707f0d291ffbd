// Force closure and the Ferrari-Canny epsilon of a set of point contacts with Coulomb friction:
// the independent measure of a grasp, used to evaluate synthesis against the true object surface.
#pragma once

#include <span>
#include <stdexcept>
#include <vector>

#include <Eigen/Core>

#include "fba/types/grasp.hpp"

namespace fba::grasp {

// Thrown for input the measure cannot be defined on: too few contacts, a zero or non-finite
// normal, coincident contacts, a non-positive torque scale, a bad friction or cone size.
class GraspQualityError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

struct QualityParams {
  double friction = 0.5;  // Coulomb coefficient mu
  int cone_edges = 8;     // each friction cone as a pyramid of this many edges
};

struct GraspQuality {
  bool force_closure = false;
  // Radius of the largest ball around the origin inside the convex hull of the contact wrenches
  // (the L1 grasp wrench space: each cone edge has a unit normal component). 0 when not force
  // closure. Forces are dimensionless; torques are divided by r_max so both are comparable.
  double epsilon = 0;
};

// The 6-D wrenches (force, torque / r_max) of every cone edge of every contact, one per column.
// Contact normals point into the object and need not be unit length (they are normalised).
Eigen::Matrix<double, 6, Eigen::Dynamic> contact_wrenches(std::span<const GraspContact> contacts,
                                                          const Eigen::Vector3d& centre_of_mass,
                                                          double r_max, const QualityParams& params = {});

// Force closure and epsilon from the convex hull (qhull) of contact_wrenches(). Throws
// GraspQualityError for degenerate input (see above); a grasp whose wrenches do not span the
// 6-D wrench space is simply not force closure.
GraspQuality evaluate_grasp(std::span<const GraspContact> contacts, const Eigen::Vector3d& centre_of_mass,
                            double r_max, const QualityParams& params = {});

}  // namespace fba::grasp
