// The grasp components run the model's surface, the candidates' search and the views' scores on
// the task's threads (SynthesisParams, ModelSurfaceParams and ExplorationParams::parallel_for):
// the results must be those of one thread, to the bit, whatever the threads' timing. Also run
// under ThreadSanitizer in CI (tools/dev.sh), which checks that the threads share nothing they write.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <vector>

#include <fba/thread_pool.hpp>

#include "fba/grasp/exploration.hpp"
#include "fba/grasp/model_surface.hpp"
#include "fba/grasp/synthesis.hpp"
#include "support/voxel_shapes.hpp"

namespace fba::grasp {
namespace {

// A can standing on the table (z = 0; its voxels reach a little below), its boundary resolved to depth 6 below 6 cm and to depth 5
// above: leaves next to finer ones, whose faces are probed at their quarters.
Octree can_on_table() {
  const Eigen::AlignedBox3d cube(Eigen::Vector3d(-0.08, -0.08, -0.02), Eigen::Vector3d(0.08, 0.08, 0.14));
  return test::voxelise(test::cylinder_sdf(0.035, -0.003, 0.1), cube, 6,
                        [](const Eigen::Vector3d& c) { return c.z() < 0.06 ? 6 : 5; });
}

TEST(GraspOnTheTasksThreads, TheSurfaceTheCandidatesAndTheViewsScoresAreThoseOfOneThread) {
  const Octree model = can_on_table();
  ThreadPool pool(3);
  const ParallelFor threads = pool.as_parallel_for();

  const ModelSurface one = model_surface(model, {0, 0.0, {}});
  const ModelSurface many = model_surface(model, {0, 0.0, threads});
  ASSERT_GT(one.samples.size(), 1000u);
  ASSERT_EQ(many.samples.size(), one.samples.size());
  EXPECT_EQ(many.leaves, one.leaves);
  EXPECT_EQ(many.unsupported_leaves, one.unsupported_leaves);
  for (std::size_t i = 0; i < one.samples.size(); ++i) {
    const auto &a = one.samples[i], &b = many.samples[i];
    ASSERT_TRUE(a.position == b.position && a.normal == b.normal && a.curvature == b.curvature && a.uncertain == b.uncertain)
        << "sample " << i;
  }

  SynthesisParams p;
  p.neighbour_radius = one.radius;
  p.table_z = 0.0;
  p.rank_total = 0.45;
  const SynthesisResult r1 = synthesise(one.samples, p);
  p.parallel_for = threads;
  const SynthesisResult rn = synthesise(one.samples, p);
  ASSERT_GT(r1.candidates.size(), 3u);
  ASSERT_EQ(rn.candidates.size(), r1.candidates.size());
  EXPECT_EQ(rn.below_table, r1.below_table);
  EXPECT_EQ(rn.hand_blocked, r1.hand_blocked);
  EXPECT_EQ(rn.not_force_closure, r1.not_force_closure);
  for (std::size_t i = 0; i < r1.candidates.size(); ++i) {
    EXPECT_EQ(rn.candidates[i].samples, r1.candidates[i].samples) << "candidate " << i;
    EXPECT_EQ(rn.candidates[i].model_epsilon, r1.candidates[i].model_epsilon) << "candidate " << i;
    EXPECT_EQ(rn.candidates[i].grasp.scores.total, r1.candidates[i].grasp.scores.total) << "candidate " << i;
  }

  // A request for the surface around the best candidate's contacts, scored from 48 views around it.
  RegionsOfInterest regions;
  for (std::size_t contact : r1.candidates.front().samples)
    for (const auto& x : one.samples)
      if ((x.position - one.samples[contact].position).norm() <= one.radius) regions.points.push_back({x.position, x.normal, 0});
  regions.boxes.push_back(model.bounds);
  std::vector<Eigen::Isometry3d> views;
  for (int i = 0; i < 48; ++i) {
    const double azimuth = 2 * std::numbers::pi * i / 12, elevation = (20 + 15 * (i / 12)) * std::numbers::pi / 180;
    const Eigen::Vector3d eye(0.3 * std::cos(elevation) * std::cos(azimuth), 0.3 * std::cos(elevation) * std::sin(azimuth),
                              0.05 + 0.3 * std::sin(elevation));
    const Eigen::Vector3d z = (Eigen::Vector3d(0, 0, 0.05) - eye).normalized();
    const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() << x, z.cross(x), z;
    pose.translation() = eye;
    views.push_back(pose);
  }
  const std::vector<Eigen::Vector3d> taken = {views[0].translation()};
  ExplorationParams e;
  const ViewChoice c1 = choose_view(model, regions, views, views[0], {}, e, taken);
  e.parallel_for = threads;
  const ViewChoice cn = choose_view(model, regions, views, views[0], {}, e, taken);
  ASSERT_TRUE(c1.best.has_value()) << c1.reason;
  EXPECT_EQ(cn.best, c1.best);
  EXPECT_EQ(cn.reason, c1.reason);
  ASSERT_EQ(cn.scores.size(), c1.scores.size());
  for (std::size_t v = 0; v < c1.scores.size(); ++v) {
    EXPECT_EQ(cn.scores[v].pins, c1.scores[v].pins) << "view " << v;
    EXPECT_EQ(cn.scores[v].first, c1.scores[v].first) << "view " << v;
    EXPECT_EQ(cn.scores[v].score, c1.scores[v].score) << "view " << v;
  }
}

}  // namespace
}  // namespace fba::grasp
