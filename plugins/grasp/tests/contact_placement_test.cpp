// A grasp placed on the true surface two ways (each contact along its normal line, and at its
// closest surface point) and counted as the worse: a contact near a box's edge lands on different
// faces by the two, one on flat faces lands the same by both.
#include <gtest/gtest.h>

#include <array>

#include "fba/geometry/mesh_io.hpp"
#include "fba/grasp/object_surface.hpp"

namespace fba::grasp {
namespace {

// A 10 cm cube centred on the origin.
ObjectSurface cube() { return ObjectSurface(geometry::make_box({-0.05, -0.05, -0.05}, {0.05, 0.05, 0.05})); }

TEST(ContactPlacement, AContactNearAnEdgeIsCountedByTheWorseOfItsTwoPlacements) {
  const ObjectSurface s = cube();
  // The thumb on the -x face; the two fingers just inside the +x face, half a millimetre under the
  // top: along their normals (-x) they reach the +x face 2 mm away, while the closest surface is
  // the top face, where they would push down.
  const std::array<GraspContact, 3> g = {GraspContact{{-0.05, 0, 0.045}, {1, 0, 0}}, GraspContact{{0.048, 0.02, 0.0495}, {-1, 0, 0}},
                                         GraspContact{{0.048, -0.02, 0.0495}, {-1, 0, 0}}};
  const GraspOnSurface on = place_grasp(s, g);
  for (int k = 1; k < 3; ++k) {
    EXPECT_TRUE(on.along_normal.contacts[k].along_normal);
    EXPECT_TRUE(on.along_normal.contacts[k].contact.normal.isApprox(Eigen::Vector3d(-1, 0, 0), 1e-6));
    EXPECT_NEAR(on.along_normal.contacts[k].contact.position.x(), 0.05, 1e-6);
    EXPECT_NEAR(on.along_normal.contacts[k].displacement, 0.002, 1e-6);
    EXPECT_FALSE(on.closest.contacts[k].along_normal);
    EXPECT_TRUE(on.closest.contacts[k].contact.normal.isApprox(Eigen::Vector3d(0, 0, -1), 1e-6));
    EXPECT_NEAR(on.closest.contacts[k].contact.position.z(), 0.05, 1e-6);
    EXPECT_NEAR(on.closest.contacts[k].displacement, 0.0005, 1e-6);
    ASSERT_TRUE(on.closest.contacts[k].normal_error_deg.has_value());
    EXPECT_NEAR(*on.closest.contacts[k].normal_error_deg, 90.0, 1e-3);
  }
  // Along the normals the fingers oppose the thumb; at the closest points all three push down or
  // sideways and nothing pushes up or back: not force closure.
  EXPECT_TRUE(on.along_normal.quality.force_closure);
  EXPECT_GT(on.along_normal.quality.epsilon, 0);
  EXPECT_FALSE(on.closest.quality.force_closure);
  EXPECT_EQ(on.closest.quality.epsilon, 0);
  EXPECT_EQ(&on.worse(), &on.closest);
  EXPECT_FALSE(on.worse().quality.force_closure);
}

TEST(ContactPlacement, ContactsOnFlatFacesLandTheSameByBothPlacements) {
  const ObjectSurface s = cube();
  // Given a millimetre off the faces, well away from any edge.
  const std::array<GraspContact, 3> g = {GraspContact{{-0.051, 0, 0}, {1, 0, 0}}, GraspContact{{0.051, 0.02, 0.01}, {-1, 0, 0}},
                                         GraspContact{{0.049, -0.02, 0.01}, {-1, 0, 0}}};
  const GraspOnSurface on = place_grasp(s, g);
  for (int k = 0; k < 3; ++k) {
    EXPECT_TRUE(on.along_normal.contacts[k].contact.position.isApprox(on.closest.contacts[k].contact.position, 1e-9)) << k;
    EXPECT_TRUE(on.along_normal.contacts[k].contact.normal.isApprox(on.closest.contacts[k].contact.normal, 1e-9)) << k;
    EXPECT_NEAR(on.along_normal.contacts[k].displacement, 0.001, 1e-6) << k;
    EXPECT_NEAR(on.closest.contacts[k].displacement, 0.001, 1e-6) << k;
  }
  EXPECT_TRUE(on.along_normal.quality.force_closure);
  EXPECT_TRUE(on.closest.quality.force_closure);
  EXPECT_DOUBLE_EQ(on.along_normal.quality.epsilon, on.closest.quality.epsilon);
  EXPECT_TRUE(on.worse().quality.force_closure);
  EXPECT_DOUBLE_EQ(on.worse().quality.epsilon, on.along_normal.quality.epsilon);
}

TEST(ContactPlacement, TheWorseOfTwoForceClosurePlacementsIsTheOneWithTheLowerEpsilon) {
  const ObjectSurface s = cube();
  // The fingers' normals tilted 30 degrees towards +z, given outside the +x face near its top edge:
  // along the tilted line they land lower on the +x face; the closest point is straight in. Both
  // placements are force closure with different contact heights, so different epsilons.
  const double c = std::cos(M_PI / 6), n = std::sin(M_PI / 6);
  const std::array<GraspContact, 3> g = {GraspContact{{-0.05, 0, 0}, {1, 0, 0}}, GraspContact{{0.052, 0.02, 0.03}, {-c, 0, n}},
                                         GraspContact{{0.052, -0.02, 0.03}, {-c, 0, n}}};
  const GraspOnSurface on = place_grasp(s, g);
  ASSERT_TRUE(on.along_normal.quality.force_closure);
  ASSERT_TRUE(on.closest.quality.force_closure);
  ASSERT_NE(on.along_normal.quality.epsilon, on.closest.quality.epsilon);
  const PlacedGrasp& lower = on.along_normal.quality.epsilon < on.closest.quality.epsilon ? on.along_normal : on.closest;
  EXPECT_EQ(&on.worse(), &lower);
}

TEST(ContactPlacement, TwoContactsSnappedToOneCornerAreNotForceClosureRatherThanAnError) {
  const ObjectSurface s = cube();
  // No normals: both placements take the closest point, the cube's corner, for the two fingers.
  const std::array<GraspContact, 3> g = {GraspContact{{-0.05, 0, 0}, {1, 0, 0}}, GraspContact{{0.06, 0.06, 0.06}, {0, 0, 0}},
                                         GraspContact{{0.07, 0.07, 0.07}, {0, 0, 0}}};
  const GraspOnSurface on = place_grasp(s, g);
  EXPECT_FALSE(on.worse().quality.force_closure);
  EXPECT_NE(on.closest.degenerate.find("contacts 1 and 2 placed on one point"), std::string::npos) << on.closest.degenerate;
  EXPECT_FALSE(on.along_normal.quality.force_closure);
}

}  // namespace
}  // namespace fba::grasp
