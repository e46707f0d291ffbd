// Grasp quality's speed, which no test asserts: evaluate_grasp (the wrenches' hull without merging,
// the merged hull where qhull reports round-off) against the merged, triangulated hull alone
// ("qhull Qt", qhull's robust default in 6-D, what evaluate_grasp ran before), on the same
// force-closure grasps in the same run.
//   build/release/bin/fba_grasp_quality_benchmark [--benchmark_repetitions=5]
#include <benchmark/benchmark.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "fba/geometry/qhull.hpp"
#include "fba/grasp/grasp_quality.hpp"

extern "C" {
#include <libqhull_r/qhull_ra.h>
}

namespace fba::grasp {
namespace {

constexpr double kRMax = 0.06;

// Three contacts on a 5 cm sphere, each pushing towards its centre give or take a random tilt, kept
// when force closure: 200 of them, the same in every run (a fixed seed).
std::vector<std::vector<GraspContact>> force_closure_grasps() {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<std::vector<GraspContact>> grasps;
  while (grasps.size() < 200) {
    std::vector<GraspContact> c(3);
    for (auto& contact : c) {
      const Eigen::Vector3d p = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized() * 0.05;
      contact = {p, -p.normalized() + 0.3 * Eigen::Vector3d(u(rng), u(rng), u(rng))};
    }
    if (evaluate_grasp(c, Eigen::Vector3d::Zero(), kRMax).force_closure) grasps.push_back(c);
  }
  return grasps;
}

void BM_EvaluateGrasp(benchmark::State& state) {
  const auto grasps = force_closure_grasps();
  std::size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(evaluate_grasp(grasps[i++ % grasps.size()], Eigen::Vector3d::Zero(), kRMax));
}
BENCHMARK(BM_EvaluateGrasp)->Unit(benchmark::kMillisecond);

// The anchor: the smallest facet distance of the merged, triangulated hull of the same wrenches.
void BM_MergedHull(benchmark::State& state) {
  std::vector<Eigen::Matrix<double, 6, Eigen::Dynamic>> wrenches;
  for (const auto& g : force_closure_grasps()) wrenches.push_back(contact_wrenches(g, Eigen::Vector3d::Zero(), kRMax));
  std::size_t i = 0;
  for (auto _ : state) {
    const auto& w = wrenches[i++ % wrenches.size()];
    std::vector<double> coords(w.data(), w.data() + w.size());
    double distance = std::numeric_limits<double>::infinity();
    geometry::run_qhull(6, coords, "qhull Qt", [&](qhT* qh) {
      facetT* facet;
      FORALLfacets { distance = std::min(distance, -facet->offset); }
    });
    benchmark::DoNotOptimize(distance);
  }
}
BENCHMARK(BM_MergedHull)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace fba::grasp

BENCHMARK_MAIN();
