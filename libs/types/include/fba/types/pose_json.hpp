// A pose as JSON in events and summary.json (the arm's targets and arrivals, the planner's views,
// reach planning's pregrasp), one shape that web/ reads: {"position": [x, y, z] metres,
// "quaternion_wxyz": [w, x, y, z]}. (The live view's pose is its own, rounded: docs/live-view.md.)
#pragma once

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

namespace fba {

nlohmann::json pose_json(const Eigen::Isometry3d& world_from_frame);

}  // namespace fba
