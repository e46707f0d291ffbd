// Reach planning's time per grasp (the target: a median under 100 ms and a 95th percentile
// under 500 ms, one core), on generated scenes: boxes of random size, place and turn on the table,
// each carved exactly at the task's resolution (4 mm leaves at depth 6), grasped across a random
// pair of opposite faces at a random height, from above tilted by up to 60 degrees, the arm
// starting 20 cm behind sim.arm's initial pose. One thread; each plan's wall time and the thread's CPU time, for the whole plan
// (the model's obstacles built, IK, lines, path, timing) and for reachable() alone; and why the
// refused grasps were refused.
//
//   fba-reach-benchmark [--grasps N] [--seed S] [--depth D] [--verbose]   (--verbose: each refusal's reason)
#include <time.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "fba/motion/reach_planner.hpp"
#include "support/voxel_shapes.hpp"
#include "support/build_paths.hpp"

using namespace fba::motion;

namespace {

double wall_now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

double cpu_now() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// The q-quantile (nearest rank) of v, in ms.
double quantile_ms(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
  return 1e3 * v[std::min(v.size() - 1, rank == 0 ? 0 : rank - 1)];
}

long option_value(const std::string& name, const std::string& text, long lo, long hi) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || errno == ERANGE || v < lo || v > hi) {
    std::fprintf(stderr, "fba-reach-benchmark: %s must be a whole number in [%ld, %ld]; found '%s'\n", name.c_str(), lo, hi, text.c_str());
    std::exit(2);
  }
  return v;
}

struct Times {
  std::vector<double> wall, cpu;
};

void print_row(const char* name, const Times& t) {
  std::printf("%-22s %6zu %10.1f %10.1f %10.1f %10.1f\n", name, t.wall.size(), quantile_ms(t.wall, 0.5), quantile_ms(t.wall, 0.95),
              quantile_ms(t.cpu, 0.5), quantile_ms(t.cpu, 0.95));
}

}  // namespace

int main(int argc, char** argv) {
  long grasps = 200, seed = 1, depth = 6;
  bool verbose = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const std::string value = i + 1 < argc ? argv[i + 1] : "";
    if (a == "--grasps") grasps = option_value(a, value, 1, 100000), ++i;
    else if (a == "--seed") seed = option_value(a, value, 1, 2147483647), ++i;
    else if (a == "--depth") depth = option_value(a, value, 3, 8), ++i;
    else if (a == "--verbose") verbose = true;
    else {
      std::fprintf(stderr, "fba-reach-benchmark: unknown option '%s'; usage: fba-reach-benchmark [--grasps N] [--seed S] [--depth D] [--verbose]\n",
                   a.c_str());
      return 2;
    }
  }

  const ReachPlanner planner(fba::test::source_dir() + "/hardware/robots/wrist_camera_arm.urdf");
  // Where the arm starts: sim.arm's initial pose drawn back 20 cm along the camera's line of sight,
  // where the open hand's fingers (25 cm past the flange) stay clear of the tallest box.
  Eigen::VectorXd initial(6);
  initial << -0.4148, -2.1223, 2.2888, -2.2234, -1.3679, -0.3644;
  const Eigen::Isometry3d flange = planner.arm().forward(initial);
  const auto back = planner.arm().inverse(Eigen::Translation3d(-0.2 * flange.linear().col(2)) * flange, initial);
  if (!back.ok) {
    std::fprintf(stderr, "fba-reach-benchmark: no start pose: %s\n", back.why.c_str());
    return 1;
  }
  const Eigen::VectorXd home = back.joints;
  const Eigen::AlignedBox3d workspace(Eigen::Vector3d(-0.13, -0.13, -0.02), Eigen::Vector3d(0.13, 0.13, 0.24));

  std::mt19937_64 random(static_cast<std::uint64_t>(seed));
  auto uniform = [&](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(random); };
  Times plan_all, plan_ok, plan_refused, reachable_all;
  std::map<std::string, int> refusals;
  std::size_t leaves = 0, searched = 0;
  const double degree = M_PI / 180;
  for (long n = 0; n < grasps; ++n) {
    // The box: its size, its place, its turn about the vertical.
    const Eigen::Vector3d size(uniform(0.04, 0.10), uniform(0.04, 0.10), uniform(0.06, 0.20));
    const Eigen::Vector3d centre(uniform(-0.04, 0.04), uniform(-0.04, 0.04), size.z() / 2);
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(uniform(-M_PI, M_PI), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const auto sdf = [&](const Eigen::Vector3d& p) { return ((turn.transpose() * (p - centre)).cwiseAbs() - size / 2).maxCoeff(); };
    const fba::Octree model = fba::grasp::test::voxelise(sdf, workspace, static_cast<int>(depth));
    // The grasp: the thumb on one face, the fingers 2 cm either side on the opposite one.
    const int axis = n % 2;
    const double side = std::uniform_int_distribution<int>(0, 1)(random) ? 1.0 : -1.0;
    const Eigen::Vector3d u = side * turn.col(axis);
    const Eigen::Vector3d approach = Eigen::AngleAxisd(uniform(-60, 60) * degree, u) * -Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d across = approach.cross(u).normalized();
    const double half = size(axis) / 2;
    const Eigen::Vector3d at = centre + Eigen::Vector3d::UnitZ() * (uniform(0.3, 0.8) * size.z() - size.z() / 2);
    fba::Grasp g;
    g.contacts[0] = {at - u * half, u};
    g.contacts[1] = {at + u * half + across * 0.02, -u};
    g.contacts[2] = {at + u * half - across * 0.02, -u};
    g.approach = approach;
    g.spread = 0.04;
    g.aperture = 2 * half + 0.02;

    double wall = wall_now(), cpu = cpu_now();
    const ReachPlan plan = planner.plan(g, model, home);
    wall = wall_now() - wall, cpu = cpu_now() - cpu;
    plan_all.wall.push_back(wall), plan_all.cpu.push_back(cpu);
    Times& by_outcome = plan.ok ? plan_ok : plan_refused;
    by_outcome.wall.push_back(wall), by_outcome.cpu.push_back(cpu);
    if (!plan.ok) ++refusals[to_string(plan.refusal)];
    if (plan.ok && !plan.figures.direct) ++searched;
    if (!plan.ok && verbose) std::printf("grasp %ld: %s\n", n, plan.why.c_str());

    wall = wall_now(), cpu = cpu_now();
    planner.reachable(g, model, home);
    reachable_all.wall.push_back(wall_now() - wall), reachable_all.cpu.push_back(cpu_now() - cpu);
    leaves += ReachPlanner::obstacles(model)->size();
  }

  std::printf("reach planning: %ld grasps on boxes of random size, place and turn (seed %ld), depth %ld (%.0f obstacle leaves a model "
              "on average), one thread\n",
              grasps, seed, depth, static_cast<double>(leaves) / static_cast<double>(grasps));
  std::printf("%-22s %6s %10s %10s %10s %10s\n", "", "count", "wall p50", "wall p95", "cpu p50", "cpu p95");
  std::printf("%-22s %6s %10s %10s %10s %10s\n", "", "", "ms", "ms", "ms", "ms");
  print_row("plan, every grasp", plan_all);
  print_row("plan, planned", plan_ok);
  print_row("plan, refused", plan_refused);
  print_row("reachable()", reachable_all);
  std::printf("paths searched (the straight joint-space line blocked): %zu of %zu planned\n", searched, plan_ok.wall.size());
  std::printf("refused:");
  for (const auto& [why, count] : refusals) std::printf(" %s %d", why.c_str(), count);
  std::printf("\n");
  return 0;
}
