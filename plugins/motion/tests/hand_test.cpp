// The hand's dimensions against the MJCF they come from, and where the palm goes for a grasp.
#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <sstream>

#include "fba/motion/hand_geometry.hpp"
#include "fba/motion/hand_placement.hpp"
#include "support/reach_scenes.hpp"

using namespace fba::motion;

namespace {

std::string mjcf() {
  std::ifstream in(fba::test::source_dir() + "/hardware/robots/three_finger_hand.xml");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// The numbers of attribute `attribute` of the element whose name attribute is `name`.
std::vector<double> numbers(const std::string& xml, const std::string& tag, const std::string& name, const std::string& attribute) {
  std::smatch element;
  const std::regex e("<" + tag + " name=\"" + name + "\"[^>]*>");
  if (!std::regex_search(xml, element, e)) return {};
  const std::string text = element.str();
  std::smatch value;
  if (!std::regex_search(text, value, std::regex(attribute + "=\"([^\"]*)\""))) return {};
  std::istringstream in(value[1].str());
  std::vector<double> out;
  for (double v; in >> v;) out.push_back(v);
  return out;
}

}  // namespace

TEST(HandGeometry, EachDimensionIsTheMjcfHands) {
  const std::string xml = mjcf();
  ASSERT_FALSE(xml.empty());
  EXPECT_EQ(numbers(xml, "geom", "palm", "size"), (std::vector<double>{hand::kPalmHalfWidth, hand::kPalmHalfDepth, hand::kPalmHalfThickness}));
  EXPECT_EQ(numbers(xml, "geom", "palm", "pos"), (std::vector<double>{0, 0, hand::kPalmCentreZ}));
  EXPECT_EQ(numbers(xml, "body", "thumb_base", "pos"), (std::vector<double>{-hand::kKnuckleX, 0, hand::kKnuckleZ}));
  EXPECT_EQ(numbers(xml, "body", "finger_a_base", "pos"), (std::vector<double>{hand::kKnuckleX, 0, hand::kKnuckleZ}));
  for (const std::string finger : {"thumb", "finger_a", "finger_b"})
    for (int k = 0; k < 3; ++k) {
      const std::string phalanx = finger + "_" + std::to_string(k + 1);
      const auto i = static_cast<std::size_t>(k);
      EXPECT_EQ(numbers(xml, "geom", phalanx, "fromto"), (std::vector<double>{0, 0, 0, 0, 0, hand::kPhalanxLength[i]})) << phalanx;
      EXPECT_EQ(numbers(xml, "geom", phalanx, "size"), (std::vector<double>{hand::kPhalanxRadius[i]})) << phalanx;
    }
  EXPECT_EQ(numbers(xml, "site", "thumb_pad", "pos"), (std::vector<double>{0, 0, hand::kPadAlongDistal}));
  EXPECT_EQ(numbers(xml, "joint", "finger_a_spread", "range"), (std::vector<double>{hand::kSpreadMin / 2, hand::kSpreadMax / 2}));
  EXPECT_EQ(numbers(xml, "joint", "finger_b_spread", "range"), (std::vector<double>{-hand::kSpreadMax / 2, -hand::kSpreadMin / 2}));
  // The closing slides' range is their class default.
  std::smatch close;
  ASSERT_TRUE(std::regex_search(xml, close, std::regex("<default class=\"close\">\\s*<joint[^>]*range=\"0 ([0-9.]+)\"")));
  EXPECT_EQ(std::stod(close[1].str()), hand::kTravel);
}

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
