// The "grasp" object of summary.json: round trip and clear errors.
#include <gtest/gtest.h>

#include "fba/grasp/grasp_json.hpp"

namespace fba::grasp {
namespace {

TEST(GraspJson, RoundTripKeepsEveryField) {
  Grasp g;
  g.contacts = {GraspContact{{0.1, 0.2, 0.3}, {-1, 0, 0}}, GraspContact{{0.4, 0.5, 0.6}, {0, 1, 0}},
                GraspContact{{0.7, 0.8, 0.9}, {0, 0, -1}}};
  g.approach = {0, 0, -1};
  g.spread = 0.05;
  g.aperture = 0.08;
  g.scores = {0.9, 0.8, 0.5, 0.73};
  g.views = {0, 3, 5};
  const Grasp back = grasp_from_json(nlohmann::json::parse(grasp_to_json(g).dump()), "test");
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(back.contacts[k].position, g.contacts[k].position);
    EXPECT_EQ(back.contacts[k].normal, g.contacts[k].normal);
  }
  EXPECT_EQ(back.approach, g.approach);
  EXPECT_EQ(back.spread, g.spread);
  EXPECT_EQ(back.aperture, g.aperture);
  EXPECT_EQ(back.scores.symmetry, 0.9);
  EXPECT_EQ(back.scores.safety_margin, 0.8);
  EXPECT_EQ(back.scores.curvature, 0.5);
  EXPECT_EQ(back.scores.total, 0.73);
  EXPECT_EQ(back.views, g.views);
}

std::string error_of(const std::string& text) {
  try {
    grasp_from_json(nlohmann::json::parse(text), "run/summary.json: grasp");
  } catch (const GraspJsonError& e) {
    return e.what();
  }
  return "no error";
}

TEST(GraspJson, MalformedGraspsSayWhatWhereAndWhatWasFound) {
  EXPECT_EQ(error_of(R"({"approach": [0, 0, 1]})"),
            R"(run/summary.json: grasp: expected a member "contacts" (3 contacts, thumb first), found {"approach":[0,0,1]})");
  EXPECT_EQ(error_of(R"({"contacts": [1, 2]})"),
            "run/summary.json: grasp.contacts: expected an array of 3 contacts (thumb first), found [1,2]");
  const std::string c = R"({"position": [0, 0, 0], "normal": [1, 0, 0]})";
  EXPECT_EQ(error_of(R"({"contacts": [)" + c + "," + c + R"(, {"position": [0, "a", 0], "normal": [1, 0, 0]}]})"),
            R"(run/summary.json: grasp.contacts[2].position[1]: expected a number, found "a")");
  EXPECT_EQ(error_of(R"({"contacts": [)" + c + "," + c + "," + c + R"(], "spread": "wide"})"),
            R"(run/summary.json: grasp.spread: expected a number, found "wide")");
  EXPECT_EQ(error_of("[]"), R"(run/summary.json: grasp: expected an object with "contacts", found [])");
}

}  // namespace
}  // namespace fba::grasp
