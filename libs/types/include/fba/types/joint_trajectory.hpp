// A timed joint trajectory: what a motion planner sends an arm's driver. Every joint reaches its
// position of a waypoint at that waypoint's time, all together.
#pragma once

#include <string>
#include <vector>

#include "fba/data_type.hpp"
#include "fba/types/robot_types_views.hpp"

namespace fba {

struct JointTrajectoryPoint {
  double time = 0.0;               // seconds after the first waypoint
  std::vector<double> positions;   // rad (revolute), m (prismatic), in the trajectory's joint order
  std::vector<double> velocities;  // rad/s, m/s, in the same order
};

struct JointTrajectory {
  std::vector<std::string> names;          // the joints, in the order of each waypoint's values
  std::vector<JointTrajectoryPoint> points;  // times increasing, the first at 0
  double stamp = 0.0;                      // seconds, on the producer's clock
};

}  // namespace fba

FBA_DATA_TYPE(fba::JointTrajectory, "fba.JointTrajectory",
              "Joint names and timed waypoints (time from the start in s, positions in rad or m, velocities): a motion "
              "every joint of an arm follows together.");
