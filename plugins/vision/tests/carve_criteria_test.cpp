// The carver's generic criterion measures a node's share over its projected hull, which does not
// depend on the viewing angle, where the share over the bounding rectangle does.
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "carve_common.hpp"
#include "fast_carve.hpp"
#include "fba/geometry/viewpoints.hpp"
#include "fba/vision/contour_extraction.hpp"
#include "fba/vision/octree_carver.hpp"
#include "fba/vision/reference_carve.hpp"

using namespace fba::vision;
using namespace fba::vision::detail;
using fba::vision::test::fast_carve;

namespace {

CarverParams with_curvature(double threshold) {
  CarverParams p;
  p.curvature_threshold = threshold;
  return p;
}

// A 640x480 camera 0.6 m from the origin, at the given azimuth and elevation (degrees), looking
// at the origin.
std::shared_ptr<fba::Frame> camera_around(double azimuth, double elevation) {
  auto f = std::make_shared<fba::Frame>();
  f->camera.width = 640, f->camera.height = 480;
  f->camera.K << 800, 0, 320, 0, 800, 240, 0, 0, 1;
  const double a = azimuth * M_PI / 180, e = elevation * M_PI / 180;
  const Eigen::Vector3d eye = 0.6 * Eigen::Vector3d(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
  f->camera.camera_from_world = fba::geometry::look_at(eye, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ());
  f->has_pose = true;
  f->image = cv::Mat::zeros(480, 640, CV_8UC3);
  return f;
}

// Three views 60 degrees apart of a disc-shaped silhouette, 120 px across.
std::vector<fba::Silhouette> disc_views() {
  std::vector<fba::Silhouette> views;
  for (double azimuth : {0.0, 60.0, 120.0}) {
    fba::Silhouette s;
    s.frame = camera_around(azimuth, 20);
    s.mask = cv::Mat::zeros(480, 640, CV_8UC1);
    cv::circle(s.mask, {320, 240}, 60, cv::Scalar(255), cv::FILLED);
    views.push_back(s);
  }
  return views;
}

// The root node of a 10 cm cube at the origin.
const Lattice kCube{Eigen::Vector3d::Constant(-0.05), 0.1};

// The root box the generic criterion's tests carve in: 12 cm around the origin.
const Eigen::AlignedBox3d kRootBox(Eigen::Vector3d::Constant(-0.06), Eigen::Vector3d::Constant(0.06));

// The generic criterion to `max_depth` at `occupancy_threshold`, every view in at once.
CarverParams generic(int max_depth, double occupancy_threshold) {
  CarverParams p;
  p.max_depth = max_depth;
  p.detail_after_views = 0;
  p.occupancy_threshold = occupancy_threshold;
  return p;
}

// The depth of the model's deepest leaf whose centre lies `within`.
int deepest(const fba::Octree& t, const Eigen::AlignedBox3d& within = kRootBox) {
  int d = 0;
  t.for_each_leaf([&](const fba::OctreeCell& c) {
    if (within.contains(c.centre)) d = std::max(d, c.depth);
  });
  return d;
}

}  // namespace

// The silhouette is the node itself (the mask is its projection): its share should be 1 from
// every direction. Over the hull it is, to within the pixels along the outline; over the
// bounding rectangle it falls to about 0.7 where the cube shows three faces.
TEST(HullShare, OfANodeIsNearlyIndependentOfTheViewingAngle) {
  double hull_lo = 1, hull_hi = 0, rect_lo = 1, rect_hi = 0;
  for (double elevation : {0.0, 20.0, 35.0})
    for (double azimuth = 0; azimuth <= 90; azimuth += 15) {
      fba::Silhouette s;
      s.frame = camera_around(azimuth, elevation);
      s.mask = cv::Mat::zeros(480, 640, CV_8UC1);
      ViewData probe = make_view([&] {
        fba::Silhouette t = s;
        t.mask = s.mask.clone();
        return t;
      }(), with_curvature(-INFINITY));
      double u[8], w[8];
      ASSERT_TRUE(project_corners_uv(probe, kCube, NodeKey{}, u, w));
      std::vector<cv::Point> pts, hull;
      for (int i = 0; i < 8; ++i) pts.emplace_back(cvRound(u[i] * 256), cvRound(w[i] * 256));
      cv::convexHull(pts, hull);
      cv::fillConvexPoly(s.mask, hull, cv::Scalar(255), cv::LINE_8, 8);
      const ViewData v = make_view(s, with_curvature(-INFINITY));
      const Occupancy rect = occupancy(v, rect_of(u, w, 0));
      ASSERT_FALSE(rect.empty());
      const double h = rect.full() ? 1.0 : hull_share(v, u, w, rect);
      hull_lo = std::min(hull_lo, h), hull_hi = std::max(hull_hi, h);
      rect_lo = std::min(rect_lo, rect.value()), rect_hi = std::max(rect_hi, rect.value());
    }
  RecordProperty("hull_share_range", std::to_string(hull_lo) + " .. " + std::to_string(hull_hi));
  RecordProperty("rectangle_share_range", std::to_string(rect_lo) + " .. " + std::to_string(rect_hi));
  EXPECT_GE(hull_lo, 0.97);
  EXPECT_LT(hull_hi - hull_lo, 0.03);
  EXPECT_LT(rect_lo, 0.8);  // the rectangle rule depended on the angle
  EXPECT_GT(rect_hi - rect_lo, 0.15);
}

// A half-plane silhouette through the node's projected centre covers half the hull from any
// direction.
TEST(HullShare, OfAHalfCoveredNodeIsAboutOneHalf) {
  for (double azimuth = 0; azimuth <= 90; azimuth += 30) {
    fba::Silhouette s;
    s.frame = camera_around(azimuth, 30);
    s.mask = cv::Mat::zeros(480, 640, CV_8UC1);
    s.mask.colRange(0, 320).setTo(255);  // the origin projects to x = 320
    const ViewData v = make_view(s, with_curvature(-INFINITY));
    double u[8], w[8];
    ASSERT_TRUE(project_corners_uv(v, kCube, NodeKey{}, u, w));
    const Occupancy rect = occupancy(v, rect_of(u, w, 0));
    EXPECT_NEAR(hull_share(v, u, w, rect), 0.5, 0.02) << azimuth;
  }
}

// Occupancy threshold 1 switches the generic criterion off: without a grasp criterion the root
// is never split. Threshold 0 splits every node on the outline.
TEST(GenericCriterion, ThresholdOneNeverSplitsAndZeroSplitsTheOutline) {
  const std::vector<fba::Silhouette> views = disc_views();
  CarverParams p = generic(5, 1);
  EXPECT_EQ(reference_carve(views, kRootBox, p).node_count, 1u);
  EXPECT_EQ(fast_carve(views, kRootBox, p)->node_count, 1u);
  p.occupancy_threshold = 0;
  EXPECT_EQ(deepest(*fast_carve(views, kRootBox, p)), 5);
}

// The paper's scheme: the generic criterion for the coarse levels, the grasp criteria for the
// detail. Below generic_depth only a region of interest splits, and the fast carver and the
// reference agree on every leaf.
TEST(GenericCriterion, BelowGenericDepthOnlyARegionOfInterestSplits) {
  const std::vector<fba::Silhouette> views = disc_views();
  CarverParams p = generic(6, 0);
  p.generic_depth = 3;
  EXPECT_EQ(deepest(*fast_carve(views, kRootBox, p)), 3);

  fba::RegionsOfInterest roi;
  const Eigen::AlignedBox3d region(Eigen::Vector3d(0.0, -0.06, -0.06), Eigen::Vector3d(0.06, 0.06, 0.06));  // x > 0 only
  roi.boxes.push_back(region);
  const auto model = fast_carve(views, kRootBox, p, roi);
  EXPECT_EQ(deepest(*model, region), 6);
  const Eigen::AlignedBox3d outside(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(-0.016, 1, 1));  // beyond the region's reach
  EXPECT_LE(deepest(*model, outside), 3);
  const fba::Octree ref = reference_carve(views, kRootBox, p, roi);
  EXPECT_EQ(count_leaf_mismatches(*model, ref), 0u);
  EXPECT_EQ(count_leaf_mismatches(ref, *model), 0u);
}

// Between 0 and 1 the criterion uses the hull's share, and the fast carver and the reference
// (which finds the projection by casting rays through the cube) agree on every leaf.
TEST(GenericCriterion, FastCarverAndReferenceAgreeAtAThresholdBetween) {
  std::vector<fba::Silhouette> views;
  for (double azimuth : {0.0, 50.0, 100.0, 150.0}) {
    fba::Silhouette s;
    s.frame = camera_around(azimuth, 25);
    s.mask = cv::Mat::zeros(480, 640, CV_8UC1);
    cv::ellipse(s.mask, {320, 240}, {90, 50}, azimuth, 0, 360, cv::Scalar(255), cv::FILLED);
    views.push_back(s);
  }
  for (double t : {0.3, 0.5, 0.7}) {
    const CarverParams p = generic(6, t);
    const auto fast = fast_carve(views, kRootBox, p);
    const fba::Octree ref = reference_carve(views, kRootBox, p);
    EXPECT_EQ(count_leaf_mismatches(*fast, ref), 0u) << t;
    EXPECT_EQ(count_leaf_mismatches(ref, *fast), 0u) << t;
    if (t < 0.5) EXPECT_GT(fast->node_count, 1u) << t;  // the criterion split something
  }
}

// The grasp criterion's contour points come from every boundary of the silhouette with one sign
// convention: on a ring, the hole's rim is concave (curvature -1/r, the normal into the hole), so
// at threshold 0 all its points are graspable and none of the convex outer circle's are.
TEST(GraspCriterion, HoleRimsAreConcaveAndCountAsGraspableContour) {
  cv::Mat ring = cv::Mat::zeros(480, 640, CV_8UC1);
  cv::circle(ring, {320, 240}, 140, cv::Scalar(255), cv::FILLED);
  cv::circle(ring, {320, 240}, 80, cv::Scalar(0), cv::FILLED);
  const ExtractionResult r = silhouette_from_mask(ring, camera_around(0, 20));
  ASSERT_TRUE(r.ok()) << r.error;
  const fba::Silhouette& s = *r.silhouette;
  ASSERT_EQ(s.holes.size(), 1u);
  const ViewData v = make_view(s, with_curvature(0.0));
  const std::int64_t all = rect_sum(v.graspable_integral, 0, 0, v.width - 1, v.height - 1);
  // Every graspable point is within the hole's rim (radius ~81), and the rim's points (1 px
  // apart along ~510 px) take as many pixels, less those that round to the same one.
  EXPECT_EQ(rect_sum(v.graspable_integral, 320 - 90, 240 - 90, 320 + 90, 240 + 90), all);
  EXPECT_GE(all, std::int64_t(0.7 * double(s.holes[0].contour.size())));
  // Without its holes' contours the same mask has no graspable point at threshold 0.
  fba::Silhouette outer_only = s;
  outer_only.holes.clear();
  const ViewData o = make_view(outer_only, with_curvature(0.0));
  EXPECT_EQ(rect_sum(o.graspable_integral, 0, 0, o.width - 1, o.height - 1), 0);
}
