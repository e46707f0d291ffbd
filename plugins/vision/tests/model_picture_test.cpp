// The pictures a run writes (fba/vision/caption.hpp, model_picture.hpp) and the model's PLY
// limited to the leaves two views saw (ply_mesh).
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "fba/geometry/mesh_io.hpp"
#include "fba/geometry/viewpoints.hpp"
#include "fba/vision/caption.hpp"
#include "fba/vision/model_picture.hpp"
#include "fba/vision/octree_carver.hpp"
#include "support/voxel_shapes.hpp"
#include "support/pictures.hpp"
#include "support/temp_dir.hpp"

namespace {

using fba::grasp::test::cylinder_sdf;
using fba::grasp::test::voxelise;

// A bottle-sized cylinder (3 cm radius, 19 cm tall) standing on z = 0 in a 26 cm workspace, as
// the grasp task carves it.
fba::Octree bottle() {
  const Eigen::AlignedBox3d workspace(Eigen::Vector3d(-0.13, -0.13, -0.02), Eigen::Vector3d(0.13, 0.13, 0.24));
  return voxelise(cylinder_sdf(0.03, 0.0, 0.19), workspace, 6);
}

// A camera 0.5 m from (0, 0, 0.1) at the given azimuth, 30 degrees up, seeing the whole bottle.
fba::CameraModel camera_at(double azimuth_deg) {
  const Eigen::Vector3d target(0, 0, 0.1);
  const Eigen::Vector3d eye = fba::geometry::spherical_eye(target, 0.5, azimuth_deg * M_PI / 180, 30 * M_PI / 180);
  return fba::geometry::make_camera(640, 480, 600, 600, 319.5, 239.5, fba::geometry::look_at(eye, target));
}

cv::Mat picture_of_size(cv::Size size, cv::Vec3b colour) { return cv::Mat(size, CV_8UC3, cv::Scalar(colour)); }

TEST(Caption, AddsBandsOfFixedHeightAboveAndBelowWithTheLegendDrawnInTheLowerOne) {
  const cv::Mat picture = picture_of_size({320, 200}, {10, 200, 10});
  fba::vision::Caption caption{"the object: view 3", "camera at (0.1, 0.2, 0.3) m", {{{0, 255, 0}, "contour", fba::vision::LegendMark::Line}}};
  const cv::Mat out = fba::vision::captioned(picture, caption);
  EXPECT_EQ(out.size(), fba::vision::captioned_size(picture.size()));
  EXPECT_EQ(out.rows, 200 + fba::vision::kCaptionHeaderRows + fba::vision::kCaptionLegendRows);
  EXPECT_GT(fba::test::legend_ink(out), 0.01);
  // The picture itself is untouched between the bands.
  cv::Mat body = out(cv::Rect(0, fba::vision::kCaptionHeaderRows, 320, 200));
  EXPECT_EQ(cv::norm(body, picture, cv::NORM_INF), 0);
}

TEST(Caption, AnEmptyLegendLeavesItsBandBlank) {
  const cv::Mat out = fba::vision::captioned(picture_of_size({320, 200}, {0, 0, 0}), {"title", "details", {}});
  EXPECT_EQ(fba::test::legend_ink(out), 0.0);
}

TEST(Caption, TurnsAGreyPictureBgrAndRefusesAnEmptyOneOrAnotherDepth) {
  EXPECT_EQ(fba::vision::captioned(cv::Mat(100, 100, CV_8UC1, cv::Scalar(128)), {}).type(), CV_8UC3);
  EXPECT_THROW(fba::vision::captioned(cv::Mat(), {}), std::invalid_argument);
  EXPECT_THROW(fba::vision::captioned(cv::Mat(10, 10, CV_32FC1), {}), std::invalid_argument);
}

TEST(Caption, ALegendTooLongForTwoRowsIsDrawnSmallerNotDropped) {
  fba::vision::Caption caption{"t", "d", {}};
  for (int i = 0; i < 12; ++i) caption.legend.push_back({{0, 0, 255}, "entry number " + std::to_string(i), fba::vision::LegendMark::Dot});
  const cv::Mat out = fba::vision::captioned(picture_of_size({400, 100}, {0, 0, 0}), caption);
  // The last entry's mark (red) is in the band's right half or second row: drawn, not cut.
  const cv::Mat band = out(fba::vision::legend_band(out.size()));
  cv::Mat red;
  cv::inRange(band, cv::Scalar(0, 0, 200), cv::Scalar(60, 60, 255), red);
  EXPECT_GT(cv::countNonZero(red(cv::Rect(0, band.rows / 2, band.cols, band.rows / 2))), 0);
}

TEST(ModelPicture, FramesTheObjectNotTheWorkspace) {
  fba::vision::ModelPictureOptions o;
  o.object = "bottle";
  for (double a : {0.0, 120.0, 240.0}) o.views.push_back(camera_at(a));
  o.table_z = 0.0;
  const cv::Mat picture = fba::vision::model_picture(bottle(), o);
  EXPECT_EQ(picture.size(), fba::vision::captioned_size(o.size));
  EXPECT_GT(fba::test::legend_ink(picture), 0.01);
  // A 6 cm by 19 cm bottle framed alone fills a good part of the picture; framed with its 26 cm
  // workspace it would fill a few percent.
  EXPECT_GT(fba::test::object_share(picture), 0.10);
}

TEST(ModelPicture, DrawsTheGraspsContactsInTheirColours) {
  fba::vision::ModelPictureOptions o;
  for (double a : {0.0, 120.0, 240.0}) o.views.push_back(camera_at(a));
  fba::Grasp g;
  for (int i = 0; i < 3; ++i) {
    const double a = i * 2 * M_PI / 3;
    g.contacts[static_cast<std::size_t>(i)] = {Eigen::Vector3d(0.03 * std::cos(a), 0.03 * std::sin(a), 0.1), -Eigen::Vector3d(std::cos(a), std::sin(a), 0)};
  }
  g.approach = Eigen::Vector3d(0, 0, -1);
  o.grasp = g;
  const cv::Mat with = fba::vision::model_picture(bottle(), o);
  o.grasp.reset();
  const cv::Mat without = fba::vision::model_picture(bottle(), o);
  // The thumb's red: in the picture with the grasp (and its legend), not in the one without.
  auto red = [](const cv::Mat& m) {
    cv::Mat mask;
    cv::inRange(m, cv::Scalar(0, 0, 200), cv::Scalar(70, 70, 255), mask);
    return cv::countNonZero(mask);
  };
  EXPECT_GT(red(with), 50);
  EXPECT_EQ(red(without), 0);
}

TEST(ModelPicture, RefusesATinySize) {
  fba::vision::ModelPictureOptions o;
  o.size = {32, 32};
  EXPECT_THROW(fba::vision::model_picture(bottle(), o), std::invalid_argument);
  EXPECT_THROW(fba::vision::views_picture(bottle(), o), std::invalid_argument);
}

TEST(ViewsPicture, DrawsEachCameraInItsColourWithALegend) {
  fba::vision::ModelPictureOptions o;
  for (double a : {0.0, 60.0, 120.0, 180.0}) o.views.push_back(camera_at(a));
  const cv::Mat picture = fba::vision::views_picture(bottle(), o);
  EXPECT_EQ(picture.size(), fba::vision::captioned_size(o.size));
  EXPECT_GT(fba::test::legend_ink(picture), 0.01);
  // The first camera blue, the last red, in the picture between the bands.
  const cv::Mat body = picture(cv::Rect(0, fba::vision::kCaptionHeaderRows, o.size.width, o.size.height));
  cv::Mat first, last;
  cv::inRange(body, cv::Scalar(200, 40, 0), cv::Scalar(255, 80, 30), first);
  cv::inRange(body, cv::Scalar(0, 40, 200), cv::Scalar(30, 80, 255), last);
  EXPECT_GT(cv::countNonZero(first), 20);
  EXPECT_GT(cv::countNonZero(last), 20);
}

TEST(ObjectName, ComesFromTheMeshsFolderOrANumberedImagesFolder) {
  EXPECT_EQ(fba::vision::object_name("data/ycb/YcbMustardBottle/model.obj"), "mustard bottle");
  EXPECT_EQ(fba::vision::object_name("sim_YcbMustardBottle"), "mustard bottle");
  EXPECT_EQ(fba::vision::object_name("data/middlebury-dino/dinoSR0001.png"), "middlebury dino");
  EXPECT_EQ(fba::vision::object_name("mug.obj"), "mug");
  EXPECT_EQ(fba::vision::object_name(""), "the object");
}

// Isolated occupied leaves, one in each corner octant of the root: each one's surface is its own
// box, 8 vertices and 12 triangles.
fba::Octree corner_leaves() {
  fba::Octree t;
  t.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(-0.1, -0.1, -0.1), Eigen::Vector3d(0.1, 0.1, 0.1));
  t.max_depth = 2;
  fba::OctreeNode* octants = t.split(t.root, fba::NodeState::Partial);
  for (int i = 0; i < 8; ++i) {
    fba::OctreeNode* k = t.split(octants[i], fba::NodeState::Empty);
    k[i].set_state(fba::NodeState::Full);  // the child at the root's corner
  }
  return t;
}

TEST(PlyLeaves, OccupiedHoldsEveryOccupiedLeafAndSeenThoseTwoViewsSawWhole) {
  const fba::Octree t = corner_leaves();
  // Two wide cameras far along +x see the whole root.
  auto camera = [](const Eigen::Vector3d& eye, double fx) {
    return fba::geometry::make_camera(200, 200, fx, fx, 99.5, 99.5, fba::geometry::look_at(eye, Eigen::Vector3d::Zero()));
  };
  const std::vector<fba::CameraModel> both{camera({1.0, 0, 0.2}, 300), camera({1.0, 0.3, 0}, 300)};
  fba::test::TempDir dir;
  fba::geometry::write_ply(fba::vision::ply_mesh(t, fba::vision::PlyLeaves::Occupied, both), dir.path() / "occupied.ply");
  const fba::TriangleMesh occupied = fba::geometry::load_mesh(dir.path() / "occupied.ply");
  EXPECT_EQ(occupied.vertices.size(), 8u * 8u);
  EXPECT_EQ(occupied.triangles.size(), 12u * 8u);
  EXPECT_EQ(fba::vision::ply_mesh(t, fba::vision::PlyLeaves::Seen, both).triangles.size(), 12u * 8u);  // both see every leaf
  // A narrow camera along y through the leaves at x, z > 0 sees those two whole, and no other.
  const std::vector<fba::CameraModel> part{camera({1.0, 0, 0.2}, 300), fba::geometry::make_camera(
      200, 200, 1800, 1800, 99.5, 99.5, fba::geometry::look_at({0.075, 1.0, 0.075}, {0.075, 0, 0.075}))};
  std::size_t twice = 0;
  t.for_each_occupied_leaf([&](const fba::OctreeCell& c) { twice += fba::vision::seen_by_two_views(c, part) ? 1 : 0; });
  ASSERT_EQ(twice, 2u);
  const fba::TriangleMesh seen = fba::vision::ply_mesh(t, fba::vision::PlyLeaves::Seen, part);
  EXPECT_EQ(seen.vertices.size(), 8u * twice);
  EXPECT_EQ(seen.triangles.size(), 12u * twice);
}

TEST(PlyLeaves, WithoutViewsEveryOccupiedLeafCountsAsSeen) {
  const fba::Octree t = corner_leaves();
  EXPECT_EQ(fba::vision::ply_mesh(t, fba::vision::PlyLeaves::Seen, {}).triangles.size(), 12u * 8u);
}

}  // namespace
