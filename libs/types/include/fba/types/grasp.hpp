// A three-fingered grasp: what grasp synthesis selects and the hand executes.
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

#include "fba/data_type.hpp"
#include "fba/types/robot_types_views.hpp"

namespace fba {

struct GraspContact {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // world coordinates, metres
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();    // unit, pointing into the object (inward)
};

// Each criterion is normalised to [0, 1], 1 best (Chinellato et al. 2005 as used by Recatala et al.).
struct GraspScores {
  double symmetry = 0;       // S1: contacts spread evenly around the object's centre
  double safety_margin = 0;  // S3: each contact well inside its graspable region
  double curvature = 0;      // S4: slightly concave above flat above convex
  double total = 0;          // the weighted combination the reliability threshold applies to
};

struct Grasp {
  // contacts[0] is the thumb; contacts[1] and contacts[2] the two fingers that oppose it.
  std::array<GraspContact, 3> contacts;
  // Unit direction in which the palm moves towards the object (world), perpendicular to the
  // thumb-to-fingers axis.
  Eigen::Vector3d approach = Eigen::Vector3d::Zero();
  // The pregrasp: spread is the distance between the two fingers (metres); aperture the opening
  // between the thumb and the fingers before closing (metres): the contacts' distance plus a
  // clearance.
  double spread = 0;
  double aperture = 0;
  // Where on the fingers the contacts lie: metres along the approach beyond the pads. 0: on the
  // pads; more: towards the fingertips, a pinch (the Robotiq's pinch mode), the hand that much
  // farther back, so that the fingers reach no lower than the contacts less a fingertip's radius
  // (a low object is taken from above without the fingers meeting the table).
  double pinch_depth = 0;
  GraspScores scores;
  std::vector<int> views;  // indices of the views whose model the grasp was synthesised on
  double stamp = 0.0;      // seconds, on the producer's clock
};

}  // namespace fba

FBA_DATA_TYPE(fba::Grasp, "fba.Grasp",
              "Three contacts (thumb first; world positions, inward normals), approach, pregrasp "
              "(spread, aperture), where on the fingers the contacts lie (pinch_depth) and the S1/S3/S4 scores with their total.");
