// Timed joint trajectories for the arms' tests (fba.JointTrajectory, what reach planning sends an
// arm): straight lines in joint space on a smooth profile and stand-stills, sampled like a plan.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include <fba/types/joint_trajectory.hpp>

namespace fba::test {

// Builds a trajectory step by step from `start` (the joints `names`, in that order), a waypoint
// every `step` s: hold() stands still, move_to() goes in a straight line on a cosine profile (at
// rest at both ends, every joint at the same share of its way, its top speed pi / 2 / seconds
// times its distance).
class TrajectoryBuilder {
 public:
  TrajectoryBuilder(std::vector<std::string> names, std::vector<double> start, double step = 0.02) : step_(step) {
    t_.names = std::move(names);
    t_.points.push_back({0.0, start, std::vector<double>(start.size(), 0.0)});
  }
  double now() const { return t_.points.back().time; }
  const std::vector<double>& at() const { return t_.points.back().positions; }
  TrajectoryBuilder& hold(double seconds) {
    const auto q = at();
    for (int k = 1, n = steps(seconds); k <= n; ++k) t_.points.push_back({now() + step_, q, std::vector<double>(q.size(), 0.0)});
    return *this;
  }
  TrajectoryBuilder& move_to(const std::vector<double>& to, double seconds) {
    const auto from = at();
    const double t0 = now();
    const int n = steps(seconds);
    for (int k = 1; k <= n; ++k) {
      const double share = 0.5 * (1 - std::cos(M_PI * k / n));
      const double rate = k == n ? 0.0 : 0.5 * M_PI / (n * step_) * std::sin(M_PI * k / n);
      fba::JointTrajectoryPoint p;
      p.time = t0 + k * step_;
      for (std::size_t j = 0; j < from.size(); ++j) {
        p.positions.push_back(from[j] + (to[j] - from[j]) * share);
        p.velocities.push_back((to[j] - from[j]) * rate);
      }
      t_.points.push_back(std::move(p));
    }
    return *this;
  }
  const fba::JointTrajectory& trajectory() const { return t_; }

 private:
  int steps(double seconds) const { return std::max(1, static_cast<int>(std::lround(seconds / step_))); }
  double step_;
  fba::JointTrajectory t_;
};

// From `from` to `to` in `seconds`, after standing still for `hold_s`.
inline fba::JointTrajectory straight_trajectory(const std::vector<std::string>& names, const std::vector<double>& from,
                                                const std::vector<double>& to, double seconds, double step = 0.02,
                                                double hold_s = 0) {
  TrajectoryBuilder b(names, from, step);
  if (hold_s > 0) b.hold(hold_s);
  return b.move_to(to, seconds).trajectory();
}

// The trajectory's positions at time t, on the straight line between its waypoints.
inline std::vector<double> position_at(const fba::JointTrajectory& t, double time) {
  const auto& p = t.points;
  if (time <= p.front().time) return p.front().positions;
  if (time >= p.back().time) return p.back().positions;
  std::size_t k = 0;
  while (p[k + 1].time < time) ++k;
  const double share = (time - p[k].time) / (p[k + 1].time - p[k].time);
  std::vector<double> q(p[k].positions.size());
  for (std::size_t j = 0; j < q.size(); ++j) q[j] = p[k].positions[j] + share * (p[k + 1].positions[j] - p[k].positions[j]);
  return q;
}

}  // namespace fba::test
