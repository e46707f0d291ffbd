// A joint trajectory as JSON, in the one shape the live view's "trajectory" (docs/live-view.md) and
// summary.json's reach.trajectory share, so that web/ draws either alike.
#pragma once

#include <cstddef>
#include <limits>

#include <nlohmann/json.hpp>

#include "fba/types/joint_trajectory.hpp"

namespace fba {

// {"names": [...], "points": [{"t": s, "positions": [...]}, ...]}: the joints' names, and each
// waypoint's time and positions (velocities follow from them). At most `max_points` waypoints,
// evenly spaced, the first and the last kept; when that leaves some out, "truncated": true and
// "point_count": all of them. `scale` > 0 rounds each number to 1/scale (a power of ten: 1e6 keeps
// a micro-radian); 0 keeps the numbers as they are.
nlohmann::json trajectory_json(const JointTrajectory& t, std::size_t max_points = std::numeric_limits<std::size_t>::max(),
                               double scale = 0);

}  // namespace fba
