// Where grasp synthesis wants the model refined: the grasp-specific carving criterion, and where
// the next view should look.
#pragma once

#include <vector>

#include <Eigen/Geometry>

#include "fba/data_type.hpp"
#include "fba/types/robot_types_views.hpp"

namespace fba {

struct RegionsOfInterest {
  std::vector<Eigen::AlignedBox3d> boxes;  // world coordinates, metres
  // Views in the model they were derived from (-1: unknown), so that a next-view planner can tell
  // a request about the newest model from one that does not know the last view yet.
  int model_views = -1;

  // Surface points no pair of views pins down yet (the best grasp candidates' unresolved contacts).
  // A silhouette fixes the surface only on its rim, so a view helps a point when its line of sight
  // grazes it: within rim_deg of the tangent plane (normal: outward, unit), and at least
  // rim_separation_deg away from the grazing lines of sight already taken (two such tangents cross
  // at the point only where the surface is). Points of one group are needed together (one grasp
  // candidate's contacts and the surface around them): a view that completes a group is worth more
  // than one that pins as many points spread over several. Empty: the request names boxes only.
  struct SurfacePoint {
    Eigen::Vector3d position = Eigen::Vector3d::Zero();  // world, metres
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();    // outward, unit
    int group = 0;                                       // e.g. the grasp candidate's rank
  };
  std::vector<SurfacePoint> points;
  double rim_deg = 15;
  double rim_separation_deg = 20;
};

}  // namespace fba

FBA_DATA_TYPE(fba::RegionsOfInterest, "fba.RegionsOfInterest",
              "World-space boxes where grasping needs more model detail, and surface points that need a grazing view.");
