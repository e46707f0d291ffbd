// A rigid transform, the one pose type every plugin exchanges.
#pragma once

#include <Eigen/Geometry>

#include "fba/data_type.hpp"
#include "fba/types/robot_types_views.hpp"

namespace fba {

// world_from_frame: maps points of the named frame into world coordinates (metres).
struct Pose {
  Eigen::Isometry3d world_from_frame = Eigen::Isometry3d::Identity();
  double stamp = 0.0;  // seconds, on the producer's clock
};

}  // namespace fba

FBA_DATA_TYPE(fba::Pose, "fba.Pose", "A rigid transform world_from_frame (metres) with a time stamp.");
