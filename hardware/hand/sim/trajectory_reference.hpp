// The lift test's reference for the arm's joints: a planned trajectory sampled at any time, and the
// stretches of it after the fingers close.
#pragma once

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include <fba/types/joint_trajectory.hpp>

namespace fba::sim_hand {

// A trajectory sampled between its waypoints by cubic Hermite interpolation of their positions
// and velocities: the reference the arm's joints follow, with its velocity and acceleration.
class Reference {
 public:
  Reference(const JointTrajectory& t, const std::vector<int>& column) : n_(column.size()) {
    for (const auto& p : t.points) {
      times_.push_back(p.time);
      Eigen::VectorXd q(static_cast<Eigen::Index>(n_)), v = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(n_));
      for (std::size_t i = 0; i < n_; ++i) {
        q(static_cast<Eigen::Index>(i)) = p.positions[static_cast<std::size_t>(column[i])];
        if (!p.velocities.empty()) v(static_cast<Eigen::Index>(i)) = p.velocities[static_cast<std::size_t>(column[i])];
      }
      q_.push_back(q);
      v_.push_back(v);
    }
  }
  double end() const { return times_.back(); }
  const Eigen::VectorXd& position(std::size_t i) const { return q_[i]; }
  std::size_t size() const { return times_.size(); }
  double time(std::size_t i) const { return times_[i]; }

  void sample(double t, Eigen::VectorXd& q, Eigen::VectorXd& v, Eigen::VectorXd& a) {
    if (t <= times_.front() || times_.size() == 1) return hold(0, q, v, a);
    if (t >= times_.back()) return hold(times_.size() - 1, q, v, a);
    while (cursor_ + 1 < times_.size() && times_[cursor_ + 1] <= t) ++cursor_;
    while (cursor_ > 0 && times_[cursor_] > t) --cursor_;
    const std::size_t i = cursor_;
    const double dt = times_[i + 1] - times_[i];
    const double s = (t - times_[i]) / dt;
    const double s2 = s * s, s3 = s2 * s;
    const Eigen::VectorXd &p0 = q_[i], &p1 = q_[i + 1];
    const Eigen::VectorXd m0 = v_[i] * dt, m1 = v_[i + 1] * dt;
    q = (2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * m0 + (-2 * s3 + 3 * s2) * p1 + (s3 - s2) * m1;
    v = ((6 * s2 - 6 * s) * p0 + (3 * s2 - 4 * s + 1) * m0 + (-6 * s2 + 6 * s) * p1 + (3 * s2 - 2 * s) * m1) / dt;
    a = ((12 * s - 6) * p0 + (6 * s - 4) * m0 + (-12 * s + 6) * p1 + (6 * s - 2) * m1) / (dt * dt);
  }

 private:
  void hold(std::size_t i, Eigen::VectorXd& q, Eigen::VectorXd& v, Eigen::VectorXd& a) const {
    q = q_[i];
    v = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(n_));
    a = v;
  }
  std::size_t n_;
  std::vector<double> times_;
  std::vector<Eigen::VectorXd> q_, v_;
  std::size_t cursor_ = 0;
};

// The stretches of the plan after the fingers close: the hand's wait, the lift (the first motion),
// the hold (the still stretch after it); each an end time on the trajectory.
struct Phases {
  double lift_start = 0, lift_end = 0, hold_end = 0;
};

inline Phases phases_after(const Reference& r, double close) {
  auto moving = [&](std::size_t i) { return (r.position(i + 1) - r.position(i)).cwiseAbs().maxCoeff() > 1e-12; };
  Phases p;
  p.lift_start = p.lift_end = p.hold_end = r.end();
  std::size_t i = 0;
  while (i + 1 < r.size() && (r.time(i) < close - 1e-9 || !moving(i))) ++i;
  if (i + 1 >= r.size()) return p;
  p.lift_start = r.time(i);
  while (i + 1 < r.size() && moving(i)) ++i;
  p.lift_end = r.time(i);
  while (i + 1 < r.size() && !moving(i)) ++i;
  p.hold_end = r.time(i);
  return p;
}

}  // namespace fba::sim_hand
