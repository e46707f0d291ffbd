// tasks/grasp_dino.yaml run headless on the real Middlebury dino: the loop ends with a selected
// grasp on the object, after fewer views than the whole recorded ring, each view asked for once.
#include <gtest/gtest.h>

#include <filesystem>
#include <set>

#include <nlohmann/json.hpp>

#include <fba/task.hpp>
#include <fba/types/frame.hpp>
#include <fba/types/octree.hpp>
#include <fba/types/pose.hpp>
#include <fba/types/silhouette.hpp>

#include "fba/geometry/viewpoints.hpp"
#include "support/built_plugins.hpp"
#include "support/temp_dir.hpp"
#include "support/build_paths.hpp"

namespace {

using fba::test::built_plugins;

// The providers' bounding box of the dino (README.txt), as in the task file.
const Eigen::AlignedBox3d kDinoBox(Eigen::Vector3d(-0.061897, -0.018874, -0.057845), Eigen::Vector3d(0.010897, 0.068227, 0.015495));

}  // namespace

TEST(GraspDinoTask, SelectsAGraspOnTheDinoWithFewerViewsThanTheRing) {
  fba::RunOptions o;
  o.executor = fba::ExecutorKind::Deterministic;
  o.timeout_s = 300;
  const fba::test::TempDir out;
  o.output_dir = out.path();
  fba::Task task(fba::load_task(fba::test::tasks_dir() + "/grasp_dino.yaml", built_plugins()), o);
  const auto& frames = task.tap("views.frame");
  const auto& silhouettes = task.tap("contours.silhouette");
  const auto& targets = task.tap("planner.target");
  const auto r = task.run();
  ASSERT_EQ(r.outcome, fba::Outcome::Success) << r.reason;
  ASSERT_TRUE(r.final_event.has_value());
  EXPECT_EQ(r.final_event->name, "grasp_selected");

  // Fewer views than the 15 recorded ones, each served once, one per target the planner asked for.
  const std::size_t served = frames.size();
  RecordProperty("views_used", std::to_string(served));
  EXPECT_GE(served, 3u);
  EXPECT_LT(served, 15u);
  std::set<int> indices;
  for (const auto& f : frames) indices.insert(f.get<fba::Frame>().index);
  EXPECT_EQ(indices.size(), served);
  EXPECT_GE(targets.size(), served);
  // Beyond the three initial views, the planner chose where to look.
  int chosen = 0;
  for (const auto& e : r.events) chosen += e.name == "view_chosen";
  EXPECT_GE(chosen, 1);
  EXPECT_EQ(targets.size(), std::size_t(3 + chosen));
  // The model of every iteration was written, named by its view count, up to the one the grasp
  // was selected on (the planner's last model was written before; the selection's was not).
  for (std::size_t v = 3; v <= served; ++v)
    EXPECT_TRUE(std::filesystem::is_regular_file(out.path() / "exploration" / ("model_" + std::to_string(v) + "views.ply"))) << v;
  std::size_t written = 0;
  for (const auto& f : std::filesystem::directory_iterator(out.path() / "exploration")) written += f.path().extension() == ".ply";
  EXPECT_LE(written, served);

  // The grasp: three contacts on the dino, each inside every silhouette it was carved from (with
  // a few pixels for the model's voxels), scored at the synthesis threshold or above.
  const auto g = nlohmann::json::parse(r.final_event->payload);
  ASSERT_EQ(g.at("contacts").size(), 3u);
  EXPECT_GE(g.at("scores").at("total").get<double>(), 0.55);  // the task's threshold
  for (const auto& c : g.at("contacts")) {
    const auto p = c.at("position");
    const Eigen::Vector3d x(p[0].get<double>(), p[1].get<double>(), p[2].get<double>());
    const Eigen::Vector3d m = Eigen::Vector3d::Constant(0.005);
    EXPECT_TRUE(Eigen::AlignedBox3d(kDinoBox.min() - m, kDinoBox.max() + m).contains(x)) << x.transpose();
    for (const auto& sp : silhouettes) {
      const auto& s = sp.get<fba::Silhouette>();
      Eigen::Vector2d px;
      ASSERT_TRUE(fba::geometry::project(s.frame->camera, x, px));
      const int margin = 8;
      const int u = static_cast<int>(std::lround(px.x())), v = static_cast<int>(std::lround(px.y()));
      bool inside = false;
      for (int dv = -margin; dv <= margin && !inside; ++dv)
        for (int du = -margin; du <= margin && !inside; ++du) {
          const int uu = u + du, vv = v + dv;
          inside = uu >= 0 && vv >= 0 && uu < s.mask.cols && vv < s.mask.rows && s.mask.at<unsigned char>(vv, uu) > 0;
        }
      EXPECT_TRUE(inside) << "contact " << x.transpose() << " projects to " << px.transpose() << ", off the silhouette of view "
                          << s.frame->index;
    }
  }
}
