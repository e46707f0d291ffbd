// A three-fingered grasp: what grasp synthesis selects and the hand executes.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <vector>

#include <Eigen/Geometry>

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

// The candidates one analysis of grasp synthesis weighed, in the order it weighs them (reliable
// first, the most stable on the model first), the first few of them: what a live view draws while
// the search goes on.
struct GraspCandidates {
  struct Candidate {
    Grasp grasp;
    bool reliable = false;     // its contacts and the surface around them resolved
    bool passed_over = false;  // the arm's reach check passed it over
    // The palm at the pregrasp (world_from_palm), for the best candidate only: the one selected on
    // this model, else the first the arm's reach check did not pass over.
    std::optional<Eigen::Isometry3d> palm;
  };
  std::vector<Candidate> candidates;
  std::size_t total = 0;  // candidates the analysis found, those left out here included
  int views = 0;          // the views of the model analysed
  double stamp = 0.0;     // seconds, on the producer's clock
};

}  // namespace fba

FBA_DATA_TYPE(fba::Grasp, "fba.Grasp",
              "Three contacts (thumb first; world positions, inward normals), approach, pregrasp "
              "(spread, aperture), where on the fingers the contacts lie (pinch_depth) and the S1/S3/S4 scores with their total.");
FBA_DATA_TYPE(fba::GraspCandidates, "fba.GraspCandidates",
              "The first candidates of one grasp analysis, best first: each grasp, whether it is reliable and whether the arm's "
              "reach check passed it over, and the best one's palm at the pregrasp.");
