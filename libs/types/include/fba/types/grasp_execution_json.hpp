// What executing a grasp did, as JSON: the payload of every hand driver's held and dropped events,
// so that sim.hand's and hw.robotiq_3f's read alike.
#pragma once

#include <nlohmann/json.hpp>

#include "fba/types/grasp_execution.hpp"

namespace fba {

// {"held", "hold_s", "reason", "contacts": [{"link", "position": [x, y, z], "normal": [x, y, z],
// "force"}]}: what every hand reports. A simulation, which measures them, adds slip_m and
// lift_height_m itself; a real hand does not know them.
nlohmann::json grasp_execution_json(const GraspExecution& e);

}  // namespace fba
