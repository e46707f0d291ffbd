// Timed joint trajectories for the arms' tests (fba.JointTrajectory, what reach planning sends an
// arm): a straight line in joint space on a smooth profile, sampled like a plan.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include <fba/types/joint_trajectory.hpp>

namespace fba::test {

// From `from` to `to` (the joints `names`, in that order) in `seconds`, after standing still for
// `hold_s`; a waypoint every `step` s. Every joint covers the same share of its way at each
// waypoint, on a cosine profile: at rest at both ends, its top speed pi / 2 / seconds times its
// distance.
inline fba::JointTrajectory straight_trajectory(const std::vector<std::string>& names, const std::vector<double>& from,
                                                const std::vector<double>& to, double seconds, double step = 0.02,
                                                double hold_s = 0) {
  fba::JointTrajectory t;
  t.names = names;
  const int holds = static_cast<int>(std::lround(hold_s / step)), moves = static_cast<int>(std::lround(seconds / step));
  for (int k = 0; k <= holds + moves; ++k) {
    const double time = k * step;
    const double share = k <= holds ? 0.0 : 0.5 * (1 - std::cos(M_PI * (k - holds) / moves));
    const double rate = k <= holds || k == holds + moves ? 0.0 : 0.5 * M_PI / seconds * std::sin(M_PI * (k - holds) / moves);
    fba::JointTrajectoryPoint p;
    p.time = time;
    for (std::size_t j = 0; j < from.size(); ++j) {
      p.positions.push_back(from[j] + (to[j] - from[j]) * share);
      p.velocities.push_back((to[j] - from[j]) * rate);
    }
    t.points.push_back(std::move(p));
  }
  return t;
}

}  // namespace fba::test
