// The convex hull's volume, and the convexity test the lift test uses to collide a convex object as
// its hull: every generated family's convex shapes pass it (superquadrics' exponents are at most
// 2), the concave ones do not.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "fba/geometry/convex_hull.hpp"
#include "fba/geometry/mesh_io.hpp"
#include "fba/geometry/object_families.hpp"
#include "support/u_shape.hpp"

namespace fba::geometry {
namespace {

double share_of_hull(const TriangleMesh& mesh) { return std::abs(signed_volume(mesh)) / convex_hull(mesh).volume; }

TEST(ConvexHull, ABoxIsItsOwnHull) {
  const TriangleMesh box = make_box_shape(0.1, 0.06, 0.02);
  const ConvexHull hull = convex_hull(box);
  EXPECT_NEAR(hull.volume / (0.1 * 0.06 * 0.02), 1.0, 1e-6);  // float vertices
  EXPECT_EQ(hull.vertices.size(), 8u);
  EXPECT_NEAR(share_of_hull(box), 1.0, 1e-9);
}

TEST(ConvexHull, ConvexShapesPassTheConvexityTestAndConcaveOnesDoNot) {
  EXPECT_GE(share_of_hull(make_cylinder_shape(0.03, 0.1)), kConvexVolumeShare);
  EXPECT_GE(share_of_hull(make_superquadric_shape(Eigen::Vector3d(0.05, 0.04, 0.03), 1, 1)), kConvexVolumeShare);
  EXPECT_GE(share_of_hull(make_superquadric_shape(Eigen::Vector3d(0.05, 0.04, 0.03), 0.3, 1.8)), kConvexVolumeShare);
  // The U's gap is a third of its hull.
  EXPECT_LT(share_of_hull(fba::test::make_u_shape(fba::test::UShape{})), kConvexVolumeShare);
}

TEST(ConvexHull, EveryGeneratedConvexFamilyIsConvexAndEveryConcaveOneIsNot) {
  for (ObjectFamily family : all_families())
    for (int index = 0; index < 5; ++index) {
      const FamilyObject object = make_family_object(family, 31, index);
      const bool convex = family == ObjectFamily::box || family == ObjectFamily::cylinder || family == ObjectFamily::sphere ||
                          family == ObjectFamily::ellipsoid || family == ObjectFamily::superquadric;
      const double share = share_of_hull(object.mesh);
      if (convex) EXPECT_GE(share, kConvexVolumeShare) << object.name;
      if (family == ObjectFamily::ring || family == ObjectFamily::holed || family == ObjectFamily::l_shape ||
          family == ObjectFamily::t_shape || family == ObjectFamily::tool)
        EXPECT_LT(share, kConvexVolumeShare) << object.name;
    }
}

TEST(ConvexHull, PointsThatSpanNoVolumeAreRefused) {
  TriangleMesh flat;
  flat.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  EXPECT_THROW(convex_hull(flat), ConvexHullError);
  EXPECT_THROW(convex_hull(TriangleMesh{}), ConvexHullError);
}

// A square with points inside it, on its edges and repeated: its four corners, counter-clockwise
// from the lowest x and y.
TEST(ConvexHull2d, ASquaresCornersCounterClockwiseAndNothingElse) {
  std::vector<Eigen::Vector2d> points{{1, 1}, {0, 0}, {0.5, 0.5}, {1, 0}, {0, 1}, {0.5, 0}, {0, 0.5}, {1, 1}, {0.2, 0.7}};
  const std::vector<Eigen::Vector2d> hull = convex_hull_2d(points);
  const std::vector<Eigen::Vector2d> expected{{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  ASSERT_EQ(hull.size(), expected.size());
  for (std::size_t i = 0; i < hull.size(); ++i) EXPECT_EQ(hull[i], expected[i]) << "corner " << i;
}

TEST(ConvexHull2d, FewerThanThreeDistinctPointsComeBackSorted) {
  EXPECT_TRUE(convex_hull_2d({}).empty());
  const auto two = convex_hull_2d({{1, 0}, {0, 0}, {1, 0}});
  ASSERT_EQ(two.size(), 2u);
  EXPECT_EQ(two[0], Eigen::Vector2d(0, 0));
  EXPECT_EQ(two[1], Eigen::Vector2d(1, 0));
}

}  // namespace
}  // namespace fba::geometry
