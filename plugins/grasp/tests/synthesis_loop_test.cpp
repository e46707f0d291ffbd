// grasp.synthesis in a task: the dino's views carved, the model analysed after every update, its
// regions of interest fed back to the carver's grasp criterion, the task ended by its events.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <fba/task.hpp>
#include <fba/task_config.hpp>
#include <fba/types/grasp.hpp>
#include <fba/types/regions_of_interest.hpp>

#include "fba/grasp/grasp_json.hpp"
#include "support/built_plugins.hpp"
#include "support/data_sets.hpp"

namespace {

using fba::test::built_plugins;

std::string loop_task(const std::string& synthesis_params) {
  return R"(task: grasp_loop
components:
  views:
    type: vision.image_set
    params: { file: )" + fba::test::kDinoPar + R"(, good_only: true }
  contours:
    type: vision.contour_extraction
    params: { method: fixed, threshold: 0.19, dilate: 10, erode: 7 }
  carver:
    type: vision.octree_carver
    params: { max_depth: 6, detail_after_views: 4, occupancy_threshold: 0, bounds: [-0.061897, -0.018874, -0.057845, 0.010897, 0.068227, 0.015495] }
  synthesis:
    type: grasp.synthesis
    params: )" + synthesis_params + R"(
connections:
  - views.frame -> contours.frame
  - contours.silhouette -> carver.silhouette
  - contours.silhouette -> synthesis.silhouette
  - carver.octree -> synthesis.octree
  - { from: synthesis.regions, to: carver.regions, feedback: true }
on:
  synthesis.grasp_selected: stop_success
  synthesis.grasp_synthesis_failed: stop_failure
)";
}

fba::RunOptions deterministic() {
  fba::RunOptions o;
  o.executor = fba::ExecutorKind::Deterministic;
  o.timeout_s = 300;
  return o;
}

TEST(GraspSynthesisLoop, TheDinoLoopEndsWithASelectedGraspOnTheModel) {
  fba::Task task(fba::load_task_text(loop_task("{ max_views: 15 }"), "loop.yaml", ".", built_plugins()), deterministic());
  const auto& grasps = task.tap("synthesis.grasp");
  const auto& regions = task.tap("synthesis.regions");
  const auto r = task.run();
  ASSERT_EQ(r.outcome, fba::Outcome::Success) << r.reason;
  ASSERT_TRUE(r.final_event);
  EXPECT_EQ(r.final_event->name, "grasp_selected");
  ASSERT_EQ(grasps.size(), 1u);
  const auto& g = grasps[0].get<fba::Grasp>();
  EXPECT_GE(g.scores.total, 0.45);
  EXPECT_FALSE(g.views.empty());
  // The event's payload is the grasp itself.
  const auto from_event = fba::grasp::grasp_from_json(nlohmann::json::parse(r.final_event->payload), "final event");
  EXPECT_EQ(from_event.contacts[1].position, g.contacts[1].position);
  // The models before it were not resolved enough: each asked for detail where its candidates were.
  int planned = 0;
  for (const auto& e : r.events) planned += e.name == "planning_performed";
  EXPECT_EQ(std::size_t(planned), regions.size());
  for (const auto& p : regions) EXPECT_FALSE(p.get<fba::RegionsOfInterest>().boxes.empty());
}

TEST(GraspSynthesisLoop, AnUnreachableThresholdStopsTheTaskWithTheReason) {
  fba::Task task(fba::load_task_text(loop_task("{ max_views: 5, threshold: 1.0 }"), "loop.yaml", ".", built_plugins()),
                 deterministic());
  const auto r = task.run();
  ASSERT_EQ(r.outcome, fba::Outcome::Failure) << r.reason;
  ASSERT_TRUE(r.final_event);
  EXPECT_EQ(r.final_event->name, "grasp_synthesis_failed");
  EXPECT_EQ(r.final_event->payload.rfind("no reliable grasp after 5 views: best total ", 0), 0u) << r.final_event->payload;
  // The criteria that held the best candidate back, each by name.
  for (const char* criterion : {"(S1 symmetry ", ", S3 safety margin ", ", S4 curvature ", ") < threshold 1.000"})
    EXPECT_NE(r.final_event->payload.find(criterion), std::string::npos) << criterion << " in " << r.final_event->payload;
}

}  // namespace
