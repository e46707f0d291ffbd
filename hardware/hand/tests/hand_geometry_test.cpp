// Reach planning's hand (plugins/motion's hand_geometry.hpp, its collision shapes) against the
// robot's one description, the URDF the world the lift test runs in is generated from: the palm,
// the knuckles, the phalanges, the pads, the slides' travel and the scissor's range.
#include <gtest/gtest.h>

#include <string>

#include "arm_model.hpp"
#include "fba/motion/hand_geometry.hpp"
#include "support/wrist_camera_arm.hpp"

namespace {

using fba::arm::ArmModel;
using fba::arm::CollisionShape;
namespace hand = fba::motion::hand;

const CollisionShape& first_shape(const ArmModel& chain, const std::string& link, CollisionShape::Kind kind) {
  for (const auto& s : chain.collision_shapes())
    if (s.link == link && s.kind == kind) return s;
  throw std::runtime_error("no shape of that kind on link " + link);
}

}  // namespace

TEST(HandGeometry, EachDimensionIsTheUrdfs) {
  // From the flange, so that the palm (fixed to it) is a link of the chain with its shape.
  const ArmModel thumb(fba::test::wrist_camera_arm_urdf(), "flange", "thumb_pad");
  const ArmModel finger(fba::test::wrist_camera_arm_urdf(), "palm", "finger_a_pad");

  const CollisionShape& palm = first_shape(thumb, "palm", CollisionShape::Kind::Box);
  EXPECT_DOUBLE_EQ(palm.size.x() / 2, hand::kPalmHalfWidth);
  EXPECT_DOUBLE_EQ(palm.size.y() / 2, hand::kPalmHalfDepth);
  EXPECT_DOUBLE_EQ(palm.size.z() / 2, hand::kPalmHalfThickness);
  // The palm's shape in the palm's frame (the chain's frames are the flange's, then the palm's).
  const std::vector<Eigen::Isometry3d> at_zero = thumb.link_poses(Eigen::VectorXd::Zero(4));
  const Eigen::Isometry3d flange_from_palm = at_zero[0];
  EXPECT_NEAR((flange_from_palm.inverse() * at_zero[0] * palm.frame_from_shape).translation().z(), hand::kPalmCentreZ, 1e-12);

  // The thumb's chain, open: its carriage at the knuckle, each phalanx's length, the pad.
  const auto& links = thumb.link_names();
  auto in_palm = [&](const std::string& link) {
    for (std::size_t i = 0; i < links.size(); ++i)
      if (links[i] == link) return Eigen::Vector3d((flange_from_palm.inverse() * at_zero[i]).translation());
    throw std::runtime_error("no link " + link);
  };
  EXPECT_TRUE(in_palm("thumb_carriage").isApprox(Eigen::Vector3d(-hand::kKnuckleX, 0, hand::kKnuckleZ), 1e-12));
  EXPECT_NEAR(in_palm("thumb_2").z() - in_palm("thumb_1").z(), hand::kPhalanxLength[0], 1e-12);
  EXPECT_NEAR(in_palm("thumb_3").z() - in_palm("thumb_2").z(), hand::kPhalanxLength[1], 1e-12);
  EXPECT_NEAR(in_palm("thumb_pad").z() - in_palm("thumb_3").z(), hand::kPadAlongDistal, 1e-12);
  EXPECT_NEAR(in_palm("thumb_pad").z(), hand::kPadDistance, 1e-12);
  for (int k = 0; k < 3; ++k) {
    const CollisionShape& c = first_shape(thumb, "thumb_" + std::to_string(k + 1), CollisionShape::Kind::Cylinder);
    EXPECT_DOUBLE_EQ(c.size.x(), hand::kPhalanxRadius[static_cast<std::size_t>(k)]) << "thumb_" << k + 1;
    EXPECT_DOUBLE_EQ(c.size.y(), hand::kPhalanxLength[static_cast<std::size_t>(k)]) << "thumb_" << k + 1;
  }
  // The fingertip ends flat: the distal phalanx is capped at its joint only.
  for (const auto& s : thumb.collision_shapes())
    if (s.link == "thumb_3" && s.kind == CollisionShape::Kind::Sphere)
      EXPECT_NEAR(s.frame_from_shape.translation().norm(), 0.0, 1e-12) << "a cap away from the distal phalanx's joint";
  EXPECT_DOUBLE_EQ(thumb.limits()[0].upper, hand::kTravel);  // thumb_close

  // A finger: its knuckle, its closing slide's travel, the scissor's range (half a spread a side).
  ASSERT_EQ(finger.joint_names()[0], "finger_a_spread");
  EXPECT_DOUBLE_EQ(2 * finger.limits()[0].lower, hand::kSpreadMin);
  EXPECT_DOUBLE_EQ(2 * finger.limits()[0].upper, hand::kSpreadMax);
  EXPECT_DOUBLE_EQ(finger.limits()[1].upper, hand::kTravel);  // finger_a_close
  const Eigen::VectorXd open = (Eigen::VectorXd(5) << 0.0, 0, 0, 0, 0).finished();
  EXPECT_TRUE(finger.link_poses(open)[0].translation().isApprox(Eigen::Vector3d(hand::kKnuckleX, 0, hand::kKnuckleZ), 1e-12));
}
