// Where grasp synthesis wants the model refined: the grasp-specific carving criterion.
#pragma once

#include <vector>

#include <Eigen/Geometry>

#include "fba/data_type.hpp"

namespace fba {

struct RegionsOfInterest {
  std::vector<Eigen::AlignedBox3d> boxes;  // world coordinates, metres
  // Views in the model they were derived from (-1: unknown), so that a next-view planner can tell
  // a request about the newest model from one that does not know the last view yet.
  int model_views = -1;
};

}  // namespace fba

FBA_DATA_TYPE(fba::RegionsOfInterest, "fba.RegionsOfInterest",
              "World-space boxes where grasping needs more model detail.");
