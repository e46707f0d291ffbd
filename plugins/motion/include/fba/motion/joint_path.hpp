// A collision-free path in joint space between two joint vectors: the straight line when it is
// free, else OMPL's RRT-Connect in the box of the joint limits, shortcut with OMPL's
// PathSimplifier. Seeded: the same problem gives the same path on every run (when it is solved
// within the time limit).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "arm_model.hpp"

namespace fba::motion {

struct JointPathOptions {
  // The search's effort, in poses checked for collision: a bound that ends it at the same point on
  // any machine, so a plan is the same on a loaded one or under a sanitizer (a wall-time bound
  // was not: it failed searches there that succeed here).
  std::size_t max_checks = 20000;
  double time_limit = 30;        // s of wall time: a guard only, for a collision check gone slow
  double collision_step = 0.02;  // rad (Euclidean in joint space) between the poses checked along a motion
  std::uint32_t seed = 1;        // OMPL's random numbers
};

struct JointPath {
  bool ok = false;
  std::string why;                          // when !ok
  std::vector<Eigen::VectorXd> waypoints;   // from `from` to `to`, each motion between two free
  double planning_s = 0;                    // wall time
  bool direct = false;                      // the straight line was free
  std::size_t checks = 0;                   // poses checked for collision
};

// `collision(q)` says what the robot at q touches, or "". `from` and `to` must be free (not
// checked again). Continuous joints are searched within [-pi, pi].
JointPath plan_joint_path(const Eigen::VectorXd& from, const Eigen::VectorXd& to, const std::vector<arm::JointLimits>& limits,
                          const std::function<std::string(const Eigen::VectorXd&)>& collision, const JointPathOptions& options = {});

// What the robot touches first on the straight motion from a to b (a itself not checked), at poses
// `step` apart; "" when free. `checks` counts the poses checked.
std::string motion_collision(const Eigen::VectorXd& a, const Eigen::VectorXd& b, double step,
                             const std::function<std::string(const Eigen::VectorXd&)>& collision, std::size_t* checks = nullptr);

}  // namespace fba::motion
