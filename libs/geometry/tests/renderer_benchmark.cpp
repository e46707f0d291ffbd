// The renderer's speed, which no test asserts: a YCB mesh at 640x480 from one view.
//   build/release/bin/fba_geometry_benchmark [--benchmark_repetitions=5]
#include <benchmark/benchmark.h>

#include "fba/geometry/mesh_io.hpp"
#include "fba/geometry/renderer.hpp"
#include "fba/geometry/viewpoints.hpp"
#include "support/data_sets.hpp"

namespace fba::geometry {
namespace {

void BM_RenderYcbMeshAt640x480(benchmark::State& state) {
  const TriangleMesh mesh = load_mesh(fba::test::ycb_mesh("YcbMustardBottle"));
  const auto box = mesh_bounds(mesh);
  const auto cam = make_camera(640, 480, 600, 600, 320, 240,
                               look_at(box.center() + Eigen::Vector3d(0.35, 0.1, 0.2), box.center()));
  for (auto _ : state) benchmark::DoNotOptimize(render(mesh, cam));
  state.counters["triangles"] = static_cast<double>(mesh.triangles.size());
}
BENCHMARK(BM_RenderYcbMeshAt640x480)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace fba::geometry

BENCHMARK_MAIN();
