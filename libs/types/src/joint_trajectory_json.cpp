#include "fba/types/joint_trajectory_json.hpp"

#include <algorithm>

#include "view_json.hpp"

namespace fba {

nlohmann::json trajectory_json(const JointTrajectory& t, std::size_t max_points, double scale) {
  auto value = [scale](double v) -> nlohmann::json { return scale > 0 ? views::number(v, scale) : nlohmann::json(v); };
  const std::size_t n = t.points.size();
  const std::size_t shown = std::min(n, max_points);
  nlohmann::json points = nlohmann::json::array();
  for (std::size_t i = 0; i < shown; ++i) {
    // Evenly spaced over the whole trajectory, the first and the last included.
    const std::size_t k = shown < 2 ? i : i * (n - 1) / (shown - 1);
    nlohmann::json positions = nlohmann::json::array();
    for (double p : t.points[k].positions) positions.push_back(value(p));
    points.push_back({{"t", value(t.points[k].time)}, {"positions", std::move(positions)}});
  }
  nlohmann::json out = {{"names", t.names}, {"points", std::move(points)}};
  if (shown < n) {
    out["truncated"] = true;
    out["point_count"] = n;
  }
  return out;
}

}  // namespace fba
