// The vision tasks, run headless on the real data: what they produce meets the accuracy the
// issue asks for.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <fba/registry.hpp>

#include "support/built_plugins.hpp"
#include "support/pictures.hpp"
#include "support/temp_dir.hpp"
#include <fba/task.hpp>
#include <fba/types/octree.hpp>
#include <fba/types/silhouette.hpp>

#include "fba/geometry/mesh_io.hpp"
#include "fba/geometry/voxelize.hpp"
#include "fba/vision/contour_extraction.hpp"
#include "fba/vision/octree_carver.hpp"
#include "support/build_paths.hpp"
#include "support/data_sets.hpp"

namespace {

using fba::test::built_plugins;

fba::RunOptions deterministic() {
  fba::RunOptions o;
  o.executor = fba::ExecutorKind::Deterministic;
  o.timeout_s = 300;
  return o;
}

}  // namespace

// The task as written (depth 9) against the targets (mean >= 0.98, min >= 0.95), in every
// build: the carve takes about 8 s under the sanitizers, no longer minutes.
//
// Those IoUs are self-consistency: the model against the silhouettes it was carved from. Accuracy
// is also scored against silhouettes made another way (Otsu's threshold instead of the fixed 0.19,
// with the same clean-up), which the carve never saw and for which the issue sets no target:
// measured at depth 9, mean 0.9726 and min 0.9160. Otsu's threshold is higher on the dark shadowed
// parts, so its masks are smaller and the bound lower: it catches a model that fits its own
// silhouettes only.
// Under the sanitizers (74 s at depth 9) the same task carves to depth 7: the bounds there check that
// the run is whole, not the target, which the plain build checks.
#if FBA_TEST_SANITIZED
constexpr int kDinoDepth = 7;
constexpr double kDinoMeanIoU = 0.90, kDinoMinIoU = 0.85;
constexpr double kDinoOtsuMeanIoU = 0.85, kDinoOtsuMinIoU = 0.75;
#else
constexpr int kDinoDepth = 9;
constexpr double kDinoMeanIoU = 0.98, kDinoMinIoU = 0.95;
constexpr double kDinoOtsuMeanIoU = 0.95, kDinoOtsuMinIoU = 0.88;
#endif

TEST(VisionTasks, CarveDinoReprojectsOntoEverySilhouette) {
  fba::LoadOptions o;
  o.overrides = {{"carver.max_depth=" + std::to_string(kDinoDepth)}};
  fba::Task task(fba::load_task(fba::test::tasks_dir() + "/carve_dino.yaml", built_plugins(), o), deterministic());
  const auto& silhouettes = task.tap("contours.silhouette");
  const auto& models = task.tap("carver.octree", 1);  // a deep snapshot is large: keep the last
  const auto r = task.run();
  ASSERT_EQ(r.outcome, fba::Outcome::Success) << r.reason;
  ASSERT_EQ(silhouettes.size(), 15u);
  ASSERT_EQ(r.components[2].samples_out, 15u);  // one immutable snapshot per view
  const auto& model = models.back().get<fba::Octree>();
  EXPECT_EQ(model.views, 15);
  fba::vision::ExtractionParams otsu;
  otsu.binarise.method = fba::vision::BinariseParams::Method::Otsu;  // the providers' clean-up kept: without it Otsu
                                                                      // loses whole shadowed limbs (one view: IoU 0.44)
  double sum = 0, worst = 1, otsu_sum = 0, otsu_worst = 1;
  for (const auto& p : silhouettes) {
    const auto& s = p.get<fba::Silhouette>();
    const cv::Mat reprojected = fba::vision::reproject_mask(model, s.frame->camera);
    const double iou = fba::vision::mask_iou(reprojected, s.mask);
    sum += iou;
    worst = std::min(worst, iou);
    const auto other = fba::vision::extract_silhouette(s.frame, otsu);
    ASSERT_TRUE(other.ok()) << other.error;
    const double otsu_iou = fba::vision::mask_iou(reprojected, other.silhouette->mask);
    otsu_sum += otsu_iou;
    otsu_worst = std::min(otsu_worst, otsu_iou);
  }
  const double mean = sum / static_cast<double>(silhouettes.size());
  const double otsu_mean = otsu_sum / static_cast<double>(silhouettes.size());
  RecordProperty("reprojection_iou_mean", std::to_string(mean));
  RecordProperty("reprojection_iou_min", std::to_string(worst));
  RecordProperty("otsu_reprojection_iou_mean", std::to_string(otsu_mean));
  RecordProperty("otsu_reprojection_iou_min", std::to_string(otsu_worst));
  std::printf("re-projection IoU, depth %d: own silhouettes mean %.4f min %.4f; Otsu silhouettes mean %.4f min %.4f\n",
              kDinoDepth, mean, worst, otsu_mean, otsu_worst);
  EXPECT_GE(mean, kDinoMeanIoU);
  EXPECT_GE(worst, kDinoMinIoU);
  EXPECT_GE(otsu_mean, kDinoOtsuMeanIoU);
  EXPECT_GE(otsu_worst, kDinoOtsuMinIoU);
}

class CarveSim : public ::testing::TestWithParam<std::string> {};

INSTANTIATE_TEST_SUITE_P(Ycb, CarveSim, ::testing::Values("YcbMustardBottle", "YcbMasterChefCan", "YcbBanana", "YcbCrackerBox"));

// The whole pipeline on rendered images (contour extraction included, the root box estimated
// from the silhouettes) against the mesh's true voxelisation at the model's resolution.
// Nothing truly occupied may be carved, and the IoU target (0.90) holds. The task takes 20
// views: at 8 the cracker box's visual hull keeps wedges along its edges that no view cuts, and it
// scored 0.895 here (0.904 with perfect masks and its own box); see tasks/carve_sim.yaml. Measured
// at 20 views: mustard 0.944, can 0.941, banana 0.948, cracker box 0.938.
TEST_P(CarveSim, ModelMatchesTheMesh) {
  const std::string mesh = fba::test::ycb_mesh(GetParam());
  fba::LoadOptions o;
  o.overrides = {{"camera.mesh=" + mesh}, {"accuracy.mesh=" + mesh}};
  fba::Task task(fba::load_task(fba::test::tasks_dir() + "/carve_sim.yaml", built_plugins(), o), deterministic());
  const auto& models = task.tap("carver.octree", 1);
  const auto r = task.run();
  ASSERT_EQ(r.outcome, fba::Outcome::Success) << r.reason;
  ASSERT_FALSE(models.empty());
  const auto& model = models.back().get<fba::Octree>();
  const auto object = fba::geometry::load_mesh(mesh);
  auto truth = fba::geometry::voxelize(object, model.bounds, model.max_depth, fba::geometry::mesh_bounds(object).min().z());
  auto carved = fba::geometry::rasterize_octree(model);
  fba::geometry::clip_below(carved, fba::geometry::mesh_bounds(object).min().z());
  const double iou = fba::geometry::iou(truth, carved);
  const auto lost = fba::geometry::carved_away(truth, carved);
  RecordProperty("iou", std::to_string(iou));
  RecordProperty("carved_away", std::to_string(lost));
  EXPECT_GE(iou, 0.90) << GetParam();
  EXPECT_EQ(lost, 0u) << GetParam();
  // The task scores itself the same way (vision.model_accuracy, into summary.json's events).
  const auto accuracy = std::find_if(r.events.begin(), r.events.end(), [](const fba::Event& e) { return e.name == "accuracy"; });
  ASSERT_NE(accuracy, r.events.end());
  char own[32];
  std::snprintf(own, sizeof own, "\"voxel_iou\": %.6f,", iou);
  EXPECT_NE(accuracy->payload.find(own), std::string::npos) << accuracy->payload << " vs " << own;
  EXPECT_NE(accuracy->payload.find("\"carved_away\": 0,"), std::string::npos) << accuracy->payload;
  EXPECT_NE(accuracy->payload.find("\"mesh_inside_box\": true"), std::string::npos) << accuracy->payload;
}

// The whole simulated loop, exploration included: the planner's initial views reach the arm, the
// camera renders from where the arm took it, the model is carved, synthesis finds no contact that
// two views pin down yet and asks for views, the planner moves the arm to new ones, and once a
// grasp is selected the hand holds the object through the lift test (the mustard bottle).
TEST(GraspSimTask, TheLoopExploresBeyondTheInitialViewsAndTheSelectedGraspHolds) {
  fba::RunOptions options;
  options.executor = fba::ExecutorKind::Deterministic;
  options.timeout_s = 600;  // a hang detector only: the run takes a few seconds
  const fba::test::TempDir out;
  options.output_dir = out.path();
  fba::Task task(fba::load_task(fba::test::tasks_dir() + "/grasp_sim.yaml", built_plugins()), options);  // the link to grasp.yaml
  const auto r = task.run();
  ASSERT_TRUE(r.final_event) << r.reason;
  EXPECT_EQ(r.final_event->source, "hand") << r.reason;
  EXPECT_EQ(r.final_event->name, "held") << r.final_event->payload;
  EXPECT_EQ(r.outcome, fba::Outcome::Success) << r.reason;
  std::size_t arrivals = 0, moves = 0;
  std::string selected;
  for (const auto& e : r.events) {
    if (e.source == "synthesis" && e.name == "grasp_selected") selected = e.payload;
    arrivals += e.source == "arm" && e.name == "arrived";
    moves += e.source == "planner" && e.name == "view_chosen";
  }
  ASSERT_FALSE(selected.empty());
  EXPECT_GE(moves, 1u);
  EXPECT_GT(arrivals, 3u);  // more than the three initial views
  // The grasp names the views its model was carved from: "views":[0,1,2,...].
  const auto list = selected.find("\"views\":[");
  ASSERT_NE(list, std::string::npos) << selected;
  const auto end = selected.find(']', list);
  EXPECT_GE(std::count(selected.begin() + list, selected.begin() + end, ','), 3) << selected;  // at least 4 views
  // The run's results, as the summary lists them: the grasp, the views analysed, the carving's
  // totals and the lift test, each reported once by the component that knows it.
  auto component = [&](const std::string& name) {
    const auto it = std::find_if(r.components.begin(), r.components.end(), [&](const auto& c) { return c.name == name; });
    return it == r.components.end() ? fba::ComponentStats{} : *it;
  };
  const auto synthesis = component("synthesis");
  ASSERT_EQ(synthesis.results.count("grasp"), 1u);
  EXPECT_EQ(synthesis.results.at("grasp"), selected);
  EXPECT_EQ(synthesis.results.at("views"), std::to_string(std::count(selected.begin() + list, selected.begin() + end, ',') + 1));
  ASSERT_EQ(component("carver").results.count("carving"), 1u);
  EXPECT_NE(component("carver").results.at("carving").find("\"nodes_visited\": "), std::string::npos);
  ASSERT_EQ(component("hand").results.count("lift"), 1u);
  EXPECT_EQ(component("hand").results.at("lift"), r.final_event->payload);
  // The motor stage: reach planning's plan for the selected grasp, with the trajectory the arm and
  // the hand were sent and each step's time.
  ASSERT_EQ(component("reach").results.count("reach"), 1u);
  const auto reach = nlohmann::json::parse(component("reach").results.at("reach"));
  EXPECT_TRUE(reach.at("ok").get<bool>()) << reach.dump();
  EXPECT_EQ(reach.at("trajectory").at("names").size(), 6u);
  const auto& points = reach.at("trajectory").at("points");
  ASSERT_GT(points.size(), 2u);
  EXPECT_DOUBLE_EQ(points.back().at("t").get<double>(), reach.at("duration_s").get<double>());
  for (const char* step : {"plan", "approach", "close", "lift", "hold"}) EXPECT_TRUE(reach.at("steps_s").contains(step)) << step;
  // Its stages' times: it waited for the arm in exploration_movement, and worked in grasp_synthesis.
  ASSERT_EQ(synthesis.stages.size(), 3u);
  EXPECT_EQ(synthesis.stages[2].first, "exploration_movement");
  EXPECT_GE(synthesis.stages[2].second.entered, moves);
  EXPECT_GT(synthesis.stages[2].second.clock_s, 0.0);  // the arm's moves, on the virtual clock
  // The loop's pictures, each captioned with a legend: the whole model with the grasp, the views
  // taken, the grasp over the last camera image (the camera's size between the bands), reach
  // planning's robot at the pregrasp and at the lift, and a contour picture per view.
  for (const auto& [name, size] : {std::pair{"grasp_model.png", cv::Size(800, 600)}, std::pair{"views.png", cv::Size(800, 600)},
                                   std::pair{"grasp_view.png", cv::Size(640, 480)}, std::pair{"robot_pregrasp.png", cv::Size(800, 600)},
                                   std::pair{"robot_lift.png", cv::Size(800, 600)}})
    fba::test::expect_captioned(out.path() / name, size);
  EXPECT_GT(fba::test::object_share(cv::imread((out.path() / "grasp_model.png").string())), 0.08);
  EXPECT_GE(fba::test::expect_captioned_contours(out.path() / "contours"), 4u);  // one per view, and the grasp's model had at least 4
}
