#include "fba/motion/joint_path.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>

#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/datastructures/NearestNeighborsLinear.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/geometric/PathSimplifier.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>

namespace fba::motion {

namespace {

namespace ob = ompl::base;
namespace og = ompl::geometric;

// OMPL seeds each of its random generators from one process-wide sequence (ompl::RNG::setSeed
// takes effect once, before the first generator exists), so a plan would depend on the plans made
// before it. Each generator the search uses is seeded here instead.
class SeededSampler final : public ob::RealVectorStateSampler {
 public:
  SeededSampler(const ob::StateSpace* space, std::uint32_t seed) : ob::RealVectorStateSampler(space) { rng_.setLocalSeed(seed); }
};

class SeededRrtConnect final : public og::RRTConnect {
 public:
  SeededRrtConnect(const ob::SpaceInformationPtr& si, std::uint32_t seed) : og::RRTConnect(si) { rng_.setLocalSeed(seed); }
};

class SeededSimplifier final : public og::PathSimplifier {
 public:
  SeededSimplifier(const ob::SpaceInformationPtr& si, std::uint32_t seed) : og::PathSimplifier(si) { rng_.setLocalSeed(seed); }
};

// OMPL's progress lines ("RRTConnect: Created 12 states") would go to stderr on every plan.
void quiet_ompl() {
  static const bool once = [] {
    ompl::msg::setLogLevel(ompl::msg::LOG_WARN);
    return true;
  }();
  (void)once;
}

Eigen::VectorXd to_vector(const ob::State* s, std::size_t n) {
  const auto* v = s->as<ob::RealVectorStateSpace::StateType>();
  Eigen::VectorXd q(static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) q(static_cast<Eigen::Index>(i)) = v->values[i];
  return q;
}

// "thumb touches the model at (0.010, ...)": the same contact wherever it happens, for counting.
std::string without_place(const std::string& c) { return c.substr(0, c.find(" at (")); }

}  // namespace

std::string motion_collision(const Eigen::VectorXd& a, const Eigen::VectorXd& b, double step,
                             const std::function<std::string(const Eigen::VectorXd&)>& collision, std::size_t* checks) {
  const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / step)));
  for (int k = 1; k <= n; ++k) {
    if (checks) ++*checks;
    if (std::string c = collision(a + (b - a) * (double(k) / n)); !c.empty()) return c;
  }
  return {};
}

JointPath plan_joint_path(const Eigen::VectorXd& from, const Eigen::VectorXd& to, const std::vector<arm::JointLimits>& limits,
                          const std::function<std::string(const Eigen::VectorXd&)>& collision, const JointPathOptions& options) {
  const auto started = std::chrono::steady_clock::now();
  JointPath result;
  auto finish = [&] {
    result.planning_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    return result;
  };
  if (motion_collision(from, to, options.collision_step, collision, &result.checks).empty()) {
    result.ok = result.direct = true;
    result.waypoints = {from, to};
    return finish();
  }

  quiet_ompl();
  const std::size_t n = limits.size();
  auto space = std::make_shared<ob::RealVectorStateSpace>(static_cast<unsigned>(n));
  ob::RealVectorBounds bounds(static_cast<unsigned>(n));
  for (std::size_t i = 0; i < n; ++i) {
    bounds.setLow(static_cast<unsigned>(i), std::isfinite(limits[i].lower) ? limits[i].lower : -M_PI);
    bounds.setHigh(static_cast<unsigned>(i), std::isfinite(limits[i].upper) ? limits[i].upper : M_PI);
  }
  space->setBounds(bounds);
  const std::uint32_t seed = options.seed;
  space->setStateSamplerAllocator([seed](const ob::StateSpace* s) { return std::make_shared<SeededSampler>(s, seed); });

  // What the rejected poses touched, for the message when no path is found.
  std::map<std::string, std::size_t> rejected;
  std::size_t checked = 0;
  auto si = std::make_shared<ob::SpaceInformation>(space);
  si->setStateValidityChecker([&](const ob::State* s) {
    ++checked;
    const std::string c = collision(to_vector(s, n));
    if (!c.empty()) ++rejected[without_place(c)];
    return c.empty();
  });
  si->setStateValidityCheckingResolution(options.collision_step / space->getMaximumExtent());
  si->setup();

  ob::ScopedState<> start(space), goal(space);
  for (std::size_t i = 0; i < n; ++i) {
    start[static_cast<unsigned>(i)] = from(static_cast<Eigen::Index>(i));
    goal[static_cast<unsigned>(i)] = to(static_cast<Eigen::Index>(i));
  }
  auto problem = std::make_shared<ob::ProblemDefinition>(si);
  problem->setStartAndGoalStates(start, goal);
  auto planner = std::make_shared<SeededRrtConnect>(si, seed);
  planner->setProblemDefinition(problem);
  // Exact nearest neighbours by a linear scan: GNAT's pivots are drawn from the shared sequence.
  // (This sets the planner up.)
  planner->setNearestNeighbors<ompl::NearestNeighborsLinear>();
  const ob::PlannerStatus status = planner->solve(ob::plannerOrTerminationCondition(
      ob::timedPlannerTerminationCondition(options.time_limit),
      ob::PlannerTerminationCondition([&] { return checked >= options.max_checks; })));
  if (status != ob::PlannerStatus::EXACT_SOLUTION) {
    result.checks += checked;
    std::size_t total = 0;
    const std::pair<const std::string, std::size_t>* most = nullptr;
    for (const auto& r : rejected) {
      total += r.second;
      if (!most || r.second > most->second) most = &r;
    }
    char limit[64];
    if (checked >= options.max_checks)
      std::snprintf(limit, sizeof limit, "%zu poses checked", options.max_checks);
    else
      std::snprintf(limit, sizeof limit, "%g s", options.time_limit);
    result.why = std::string("no collision-free path found in ") + limit + ": " +
                 (most ? std::to_string(total) + " of " + std::to_string(checked) + " poses tried collide, most often " +
                             most->first + " (" + std::to_string(most->second) + ")"
                       : "the search found no pose to try");
    return finish();
  }
  auto& path = *problem->getSolutionPath()->as<og::PathGeometric>();
  SeededSimplifier simplifier(si, seed);
  simplifier.reduceVertices(path);
  simplifier.shortcutPath(path);
  result.checks += checked;
  result.ok = true;
  for (const ob::State* s : path.getStates()) result.waypoints.push_back(to_vector(s, n));
  result.waypoints.front() = from;  // exactly, not through the state's copy
  result.waypoints.back() = to;
  return finish();
}

}  // namespace fba::motion
