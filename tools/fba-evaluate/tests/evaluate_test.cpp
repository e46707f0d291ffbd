// The end-to-end synthetic evaluation with the real carver (fba::vision): YCB meshes, 8 views
// spread over the upper hemisphere, depth 6, table plane clipped.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "evaluate.hpp"
#include "fba/vision/model_picture.hpp"
#include "support/geometry_checks.hpp"
#include "support/pictures.hpp"
#include "support/temp_dir.hpp"

namespace fba::evaluate {
namespace {

class YcbCarve : public ::testing::TestWithParam<const char*> {
 protected:
  static SyntheticResult run(const char* name) {
    SyntheticParams p;  // 8 views, depth 6, elevations 0..90 degrees, table clip on
    return evaluate_synthetic(geometry::test::ycb_mesh(name), p);
  }
};

// Conservative carving: with perfect silhouettes no truly occupied voxel may be removed.
TEST_P(YcbCarve, PerfectSilhouettesCarveNoTrulyOccupiedVoxel) {
  const SyntheticResult r = run(GetParam());
  EXPECT_GT(r.voxels.truth_voxels, 1000u);
  EXPECT_EQ(r.voxels.carved_away, 0u);
  EXPECT_GE(r.voxels.model_voxels, r.voxels.truth_voxels);
}

// The accuracy target: IoU >= 0.90 against the true voxelisation after 8 views.
TEST_P(YcbCarve, EightHemisphereViewsReachIou090) {
  const SyntheticResult r = run(GetParam());
  RecordProperty("iou", std::to_string(r.voxels.iou));
  EXPECT_GE(r.voxels.iou, 0.90);
}

// With save_dir, each view's render and mask and the carved model's picture, each captioned.
TEST(Evaluate, SavedPicturesAreCaptionedAndTheModelPictureFramesTheObject) {
  fba::test::TempDir dir;
  SyntheticParams p;
  p.views = 3;
  p.depth = 5;
  p.save_dir = dir.path();
  evaluate_synthetic(geometry::test::ycb_mesh("YcbMustardBottle"), p);
  const std::string stem = "YcbMustardBottle_model";
  for (int i = 0; i < 3; ++i)
    for (const char* kind : {"_view", "_mask"})
      fba::test::expect_captioned(dir.path() / (stem + kind + std::to_string(i) + ".png"), {p.width, p.height});
  const cv::Mat model = cv::imread((dir.path() / (stem + "_carved.png")).string());
  ASSERT_FALSE(model.empty());
  EXPECT_EQ(model.size(), vision::captioned_size(vision::ModelPictureOptions{}.size));
  EXPECT_GT(fba::test::legend_ink(model), 0.01);
  EXPECT_GT(fba::test::object_share(model), 0.08);
}

INSTANTIATE_TEST_SUITE_P(Ycb, YcbCarve, ::testing::ValuesIn(geometry::test::kYcbNames));

TEST(Evaluate, CompareVoxelsClipsBothGridsAtTheTable) {
  const Eigen::AlignedBox3d cube(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 1));
  geometry::VoxelGrid truth(cube, 4), model(cube, 4);
  truth.set(1, 1, 2);
  model.set(1, 1, 2);
  model.set(1, 1, 0);  // below the table at z = 0: unseen, must not count against the model
  EXPECT_DOUBLE_EQ(compare_voxels(truth, model, std::nullopt).iou, 0.5);
  const VoxelComparison c = compare_voxels(truth, model, 0.0);
  EXPECT_DOUBLE_EQ(c.iou, 1.0);
  EXPECT_EQ(c.carved_away, 0u);
}

}  // namespace
}  // namespace fba::evaluate
