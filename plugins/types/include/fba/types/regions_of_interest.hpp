// Where grasp synthesis wants the model refined: the grasp-specific carving criterion.
#pragma once

#include <vector>

#include <Eigen/Geometry>

#include "fba/data_type.hpp"

namespace fba {

struct RegionsOfInterest {
  std::vector<Eigen::AlignedBox3d> boxes;  // world coordinates, metres
};

}  // namespace fba

FBA_DATA_TYPE(fba::RegionsOfInterest, "fba.RegionsOfInterest",
              "World-space boxes where grasping needs more model detail.");
