// The carving tasks say when their model cannot be the object, and the grasp-regions task puts
// detail only where the grasp criterion asks: the Middlebury dino, run headless.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include <opencv2/imgcodecs.hpp>

#include <fba/task.hpp>
#include <fba/types/octree.hpp>
#include <fba/types/silhouette.hpp>

#include "fba/geometry/mesh_io.hpp"
#include "fba/vision/octree_carver.hpp"

#include "support/built_plugins.hpp"
#include "support/pictures.hpp"
#include "support/temp_dir.hpp"
#include "support/build_paths.hpp"

namespace {

using fba::test::built_plugins;

fba::RunResult run(const std::string& task, std::vector<std::string> overrides, fba::RunOptions o = {}) {
  fba::LoadOptions lo;
  for (auto& s : overrides) lo.overrides.push_back({s});
  o.executor = fba::ExecutorKind::Deterministic;
  o.timeout_s = 300;
  fba::Task t(fba::load_task(fba::test::tasks_dir() + "/" + task, built_plugins(), lo), o);
  return t.run();
}

// The last event of that name (the carver's `detail` with compare_uniform comes after every update).
const fba::Event* find_event(const fba::RunResult& r, const std::string& name) {
  const fba::Event* found = nullptr;
  for (const auto& e : r.events)
    if (e.name == name) found = &e;
  return found;
}

// carve_dino at depth 6 (the checks do not depend on depth) with overrides: the run fails,
// and both the suspect_model event and the run's reason say why.
void expect_refused(const std::vector<std::string>& overrides, const std::string& why) {
  std::vector<std::string> all{"carver.max_depth=6"};
  all.insert(all.end(), overrides.begin(), overrides.end());
  const std::string override_ = overrides.front();
  const auto r = run("carve_dino.yaml", all);
  EXPECT_NE(r.outcome, fba::Outcome::Success) << override_;
  EXPECT_NE(r.reason.find(why), std::string::npos) << override_ << ": " << r.reason;
  const fba::Event* e = find_event(r, "suspect_model");
  ASSERT_NE(e, nullptr) << override_;
  EXPECT_NE(e->payload.find(why), std::string::npos) << e->payload;
}

}  // namespace

// Black images and a threshold no pixel passes are the same to the carver: no silhouette.
TEST(CarveChecks, AThresholdNoPixelPassesIsRefusedAsNoSilhouette) {
  expect_refused({"contours.threshold=1"}, "no silhouette arrived");
}

// White images (here: every pixel darker than the threshold is the object): contour extraction
// refuses a target that is the whole image.
TEST(CarveChecks, WhiteImagesAreRefusedAsNoSilhouette) {
  expect_refused({"contours.dark_object=true", "contours.threshold=1"}, "no silhouette arrived");
}

TEST(CarveChecks, OneViewIsRefusedAsAViewingCone) { expect_refused({"views.limit=1"}, "only 1 view"); }

TEST(CarveChecks, BoundsInMillimetresAreRefusedAskingForMetres) {
  expect_refused({"carver.bounds=[-61.897, -18.874, -57.845, 10.897, 68.227, 15.495]"}, "are the bounds in metres?");
}

// A threshold that leaves only the brightest patches: silhouettes with no common region.
TEST(CarveChecks, SilhouettesWithNoCommonRegionAreRefusedAsAnEmptyModel) {
  expect_refused({"contours.threshold=0.5"}, "the model is empty");
}

TEST(CarveChecks, TheDinoAsWrittenPassesEveryCheck) {
  const auto r = run("carve_dino.yaml", {"carver.max_depth=6"});
  EXPECT_EQ(r.outcome, fba::Outcome::Success) << r.reason;
  EXPECT_EQ(find_event(r, "suspect_model"), nullptr);
  EXPECT_EQ(find_event(r, "model_warning"), nullptr);
}

// With an output folder the carver writes the last model's surface (model.ply: by default the
// leaves two views saw, ply_leaves: occupied every occupied leaf), a picture of it that frames the
// object (model.png) and one of the views taken (views.png), each captioned with a legend; the
// contour extraction a captioned picture per view.
static void carve_dino_into(const std::filesystem::path& dir, const std::vector<std::string>& sets,
                     std::vector<fba::Packet>* models = nullptr, std::vector<fba::Packet>* silhouettes = nullptr) {
  fba::LoadOptions lo;
  lo.overrides = {{"carver.max_depth=6"}};
  for (const auto& s : sets) lo.overrides.push_back({s});
  fba::RunOptions o;
  o.executor = fba::ExecutorKind::Deterministic;
  o.timeout_s = 300;
  o.output_dir = dir;
  fba::Task task(fba::load_task(fba::test::tasks_dir() + "/carve_dino.yaml", built_plugins(), lo), o);
  const auto& m = task.tap("carver.octree", 1);
  const auto& s = task.tap("contours.silhouette");
  const auto r = task.run();
  ASSERT_EQ(r.outcome, fba::Outcome::Success) << r.reason;
  if (models) *models = m;
  if (silhouettes) *silhouettes = s;
}

TEST(CarveOutputs, ModelPlyHoldsTheLeavesTwoViewsSawAndThePicturesExplainThemselves) {
  fba::test::TempDir dir;
  std::vector<fba::Packet> models, silhouettes;
  carve_dino_into(dir.path(), {}, &models, &silhouettes);
  ASSERT_FALSE(models.empty());
  std::vector<fba::CameraModel> cameras;
  for (const auto& s : silhouettes) cameras.push_back(s.get<fba::Silhouette>().frame->camera);
  const fba::TriangleMesh expected =
      fba::vision::ply_mesh(models.back().get<fba::Octree>(), fba::vision::PlyLeaves::Seen, cameras);
  const fba::TriangleMesh written = fba::geometry::load_mesh(dir.path() / "model.ply");
  ASSERT_GT(expected.triangles.size(), 1000u);
  EXPECT_EQ(written.vertices, expected.vertices);
  EXPECT_EQ(written.triangles, expected.triangles);
  for (const char* name : {"model.png", "views.png"}) fba::test::expect_captioned(dir.path() / name, {800, 600});
  // The model picture frames the dino, not its surroundings.
  EXPECT_GT(fba::test::object_share(cv::imread((dir.path() / "model.png").string())), 0.08);
  // One contour picture per view, of the image's size and captioned.
  EXPECT_EQ(fba::test::expect_captioned_contours(dir.path() / "contours"), silhouettes.size());
}

TEST(CarveOutputs, PlyLeavesOccupiedWritesEveryOccupiedLeafsSurface) {
  fba::test::TempDir dir;
  std::vector<fba::Packet> models;
  carve_dino_into(dir.path(), {"carver.ply_leaves=occupied"}, &models);
  ASSERT_FALSE(models.empty());
  const fba::TriangleMesh expected = fba::vision::occupied_surface_mesh(models.back().get<fba::Octree>());
  const fba::TriangleMesh written = fba::geometry::load_mesh(dir.path() / "model.ply");
  EXPECT_EQ(written.vertices, expected.vertices);
  EXPECT_EQ(written.triangles, expected.triangles);
}

// Algorithm 2 with the grasp criterion alone: coarse where the contour is convex, fine where it
// is flat or concave. The `detail` event compares the model with uniform detail to the same
// depth, carved from the same views by the component itself.
TEST(CarveGraspRegions, KeepsFewerNodesThanUniformDetailToTheSameDepth) {
#if FBA_TEST_SANITIZED
  const std::vector<std::string> depth{"carver.max_depth=7"};
#else
  const std::vector<std::string> depth{};
#endif
  fba::LoadOptions lo;
  for (const auto& s : depth) lo.overrides.push_back({s});
  fba::RunOptions o;
  o.executor = fba::ExecutorKind::Deterministic;
  o.timeout_s = 300;
  fba::Task task(fba::load_task(fba::test::tasks_dir() + "/carve_grasp_regions.yaml", built_plugins(), lo), o);
  const auto& models = task.tap("carver.octree", 1);
  const auto r = task.run();
  ASSERT_EQ(r.outcome, fba::Outcome::Success) << r.reason;
  const fba::Event* e = find_event(r, "detail");
  ASSERT_NE(e, nullptr);
  std::size_t nodes = 0, visited = 0, uniform = 0, uniform_visited = 0;
  ASSERT_EQ(std::sscanf(e->payload.c_str(),
                        "{\"model_nodes\": %zu, \"nodes_visited\": %zu, \"uniform_nodes\": %zu, \"uniform_nodes_visited\": %zu",
                        &nodes, &visited, &uniform, &uniform_visited),
            4)
      << e->payload;
  RecordProperty("model_nodes", std::to_string(nodes));
  RecordProperty("uniform_nodes", std::to_string(uniform));
  EXPECT_LT(nodes, uniform) << e->payload;
  EXPECT_LT(visited, uniform_visited) << e->payload;
  // Coarse and fine together: leaves at the deepest level, and leaves on the outline (Partial)
  // left well above it because no flat contour point asked for them.
  ASSERT_FALSE(models.empty());
  const auto& model = models.back().get<fba::Octree>();
  EXPECT_EQ(model.node_count, nodes);
  int deepest = 0, coarse_partial = 0;
  model.for_each_leaf([&](const fba::OctreeCell& c) {
    deepest = std::max(deepest, c.depth);
    if (c.node->state() == fba::NodeState::Partial && c.depth <= model.max_depth - 2) ++coarse_partial;
  });
  EXPECT_EQ(deepest, model.max_depth);
  EXPECT_GT(coarse_partial, 0);
}
