// The positions (and velocities) of a robot's joints: what an arm publishes as it moves, and a
// joint-space target it is sent.
#pragma once

#include <string>
#include <vector>

#include "fba/data_type.hpp"
#include "fba/types/robot_types_views.hpp"

namespace fba {

struct JointState {
  // Joint names, in the order of the values; empty in a target means the arm's own order.
  std::vector<std::string> names;
  std::vector<double> positions;   // rad (revolute), m (prismatic)
  std::vector<double> velocities;  // rad/s, m/s; empty when not known (a target)
  double stamp = 0.0;              // seconds, on the producer's clock
};

}  // namespace fba

FBA_DATA_TYPE(fba::JointState, "fba.JointState",
              "Joint names with their positions (rad or m) and velocities, and a time stamp: an arm's state or a joint target.");
