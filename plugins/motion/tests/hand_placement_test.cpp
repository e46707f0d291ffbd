// Where the palm goes for a grasp (the hand's dimensions against the URDF's:
// hardware/hand/tests/hand_geometry_test.cpp).
#include <gtest/gtest.h>

#include "fba/motion/hand_geometry.hpp"
#include "fba/motion/hand_placement.hpp"
#include "support/reach_scenes.hpp"

using namespace fba::motion;

// The lift test's convention: z along the approach, x from the thumb to the fingers, the pads at
// the contacts' depth, each `clearance` out from its contact at the pregrasp's opening.
TEST(HandPlacement, ThePalmFacesAlongTheApproachWithThePadsClearOfTheContacts) {
  const Eigen::Vector3d size(0.06, 0.06, 0.10);
  const fba::Grasp g = test::box_grasp(size, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.07);
  const HandPlacement p = place_hand(g, 0.01);
  ASSERT_EQ(p.why, "");
  EXPECT_TRUE(p.world_from_palm.linear().col(2).isApprox(-Eigen::Vector3d::UnitZ()));
  EXPECT_TRUE(p.world_from_palm.linear().col(0).isApprox(Eigen::Vector3d::UnitX()));
  EXPECT_NEAR(p.width, 0.06, 1e-12);
  EXPECT_NEAR(p.spread, 0.04, 1e-12);
  EXPECT_NEAR(p.opening, 0.08, 1e-12);  // the grasp's aperture, the contacts' width plus 1 cm a side
  const auto parts = hand_parts(p.opening, p.spread);
  for (std::size_t f = 1; f < 4; ++f) {
    // The pad's inner surface, from the capsule's axis, in the world.
    const Eigen::Vector3d axis = parts[f].palm_from_part.translation();
    const double inward = axis.x() < 0 ? 1 : -1;
    const Eigen::Vector3d pad(axis.x() + inward * hand::kPadRadius, axis.y(), hand::kPadDistance);
    const Eigen::Vector3d world = p.world_from_palm * pad;
    const Eigen::Vector3d& contact = g.contacts[f - 1].position;
    EXPECT_NEAR(world.z(), contact.z(), 1e-12) << parts[f].name;
    EXPECT_NEAR(world.y(), contact.y(), 1e-12) << parts[f].name;
    EXPECT_NEAR(std::abs(world.x() - contact.x()), 0.01, 1e-12) << parts[f].name;
  }
}

TEST(HandPlacement, ContactsTheHandCannotSpanAreRefusedWithTheFigures) {
  const Eigen::Vector3d size(0.06, 0.06, 0.10);
  fba::Grasp g = test::box_grasp(size, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.07);
  fba::Grasp wide_fingers = g;
  wide_fingers.contacts[1].position.y() = 0.08;
  wide_fingers.contacts[2].position.y() = -0.08;
  EXPECT_EQ(place_hand(wide_fingers).why, "the fingers' contacts are 0.160 m apart, beyond the hand's spread of 0.120 m");
  fba::Grasp far_apart = g;
  far_apart.contacts[0].position.x() = -0.3;
  EXPECT_EQ(place_hand(far_apart).why, "the contacts are 0.330 m apart across the approach, beyond the hand's opening of 0.220 m");
  fba::Grasp along = g;
  along.approach = Eigen::Vector3d::UnitX();
  EXPECT_EQ(place_hand(along).why, "the thumb and the fingers' contacts are not apart across the approach");
  fba::Grasp none = g;
  none.approach.setZero();
  EXPECT_EQ(place_hand(none).why, "the approach direction is zero or not finite");
}
