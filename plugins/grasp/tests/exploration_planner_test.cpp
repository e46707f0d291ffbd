// grasp.exploration_planner through the component harness: the start's initial views, a request
// answered with the view that sees the region, requests held until the last target is in the
// model, no_view with its reason, recorded candidates from the dino set, configuration errors.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <optional>
#include <set>

#include <nlohmann/json.hpp>

#include <fba/task_config.hpp>
#include <fba/testing.hpp>
#include <fba/types/octree.hpp>
#include <fba/types/pose.hpp>
#include <fba/types/regions_of_interest.hpp>
#include <fba/vision/image_set.hpp>

#include "support/built_plugins.hpp"
#include "support/voxel_shapes.hpp"
#include "support/data_sets.hpp"
#include "support/events.hpp"

using fba::testing::ComponentHarness;

namespace {

using fba::test::built_plugins;
using fba::test::find_event;

// A unit box in the cube [-1, 1]^3 at depth 3: its outer layer of leaves Partial, the inside Full.
fba::Octree box_model(int views) {
  return fba::grasp::test::voxelise(fba::grasp::test::box_sdf(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones()),
                                    Eigen::AlignedBox3d(Eigen::Vector3d::Constant(-1), Eigen::Vector3d::Constant(1)), 3, {},
                                    views);
}

// A request for the box's +x face, about the model of `model_views` views (-1: unknown).
fba::RegionsOfInterest plus_x_face(int model_views = -1) {
  fba::RegionsOfInterest request{{Eigen::AlignedBox3d(Eigen::Vector3d(0.3, -0.3, -0.3), Eigen::Vector3d(0.45, 0.3, 0.3))}};
  request.model_views = model_views;
  return request;
}

// A ring of 8 views at distance 4 around the origin, in the horizontal plane: view i at azimuth i * 45 deg.
fba::testing::Params ring8(fba::testing::Params extra = {}) {
  fba::testing::Params p{{"views", std::string("ring")},  {"count", 8},
                         {"distance", 4.0},                {"min_elevation_deg", 0.0},
                         {"max_elevation_deg", 0.0},       {"centre", std::vector<double>{0, 0, 0}}};
  for (auto& [k, v] : extra) p[k] = v;
  return p;
}

int azimuth_deg(const fba::Pose& p) {
  const Eigen::Vector3d t = p.world_from_frame.translation();
  return static_cast<int>(std::lround(std::atan2(t.y(), t.x()) * 180 / std::numbers::pi + 360)) % 360;
}

}  // namespace

TEST(ExplorationPlanner, StartRequestsTheFirstCandidateAndItsNearestNeighbours) {
  ComponentHarness h(built_plugins(), "grasp.exploration_planner", ring8(), {"start"});
  h.push<std::int64_t>("start", 0);
  h.run();
  const auto targets = h.values<fba::Pose>("target");
  ASSERT_EQ(targets.size(), 3u);
  std::set<int> azimuths;
  for (const auto& t : targets) azimuths.insert(azimuth_deg(t));
  EXPECT_EQ(azimuths, (std::set<int>{0, 45, 315}));
  // The camera looks at the centre: its z axis points from its position to the origin.
  const Eigen::Isometry3d& first = targets[0].world_from_frame;
  EXPECT_TRUE((first.linear().col(2) + first.translation().normalized()).norm() < 1e-9);
}

TEST(ExplorationPlanner, SpreadStartRequestsViewsAroundTheObject) {
  ComponentHarness h(built_plugins(), "grasp.exploration_planner", ring8({{"initial_layout", std::string("spread")}}), {"start"});
  h.push<std::int64_t>("start", 0);
  h.run();
  const auto targets = h.values<fba::Pose>("target");
  ASSERT_EQ(targets.size(), 3u);
  // Candidate 0, the one opposite it, then the first of the two a quarter turn from both.
  EXPECT_EQ(azimuth_deg(targets[0]), 0);
  EXPECT_EQ(azimuth_deg(targets[1]), 180);
  EXPECT_EQ(azimuth_deg(targets[2]) % 180, 90);
}

TEST(ExplorationPlanner, ARequestGetsTheViewThatSeesTheRegion) {
  ComponentHarness h(built_plugins(), "grasp.exploration_planner", ring8());
  h.push<fba::Octree>("octree", box_model(1));
  h.push<fba::RegionsOfInterest>("regions", plus_x_face());
  h.run();
  const auto targets = h.values<fba::Pose>("target");
  ASSERT_EQ(targets.size(), 1u);
  EXPECT_EQ(azimuth_deg(targets[0]), 0);
  EXPECT_NEAR(targets[0].world_from_frame.translation().x(), 4.0, 1e-9);
  const auto chosen = find_event(h.events(), "view_chosen");
  ASSERT_TRUE(chosen.has_value());
  const auto j = nlohmann::json::parse(chosen->payload);
  EXPECT_EQ(j.at("view"), 0);
  EXPECT_EQ(j.at("seen"), 16);
  EXPECT_NEAR(j.at("pose").at("position")[0].get<double>(), 4.0, 1e-9);
  EXPECT_NE(j.at("reason").get<std::string>().find("sees 16 of the 16"), std::string::npos) << chosen->payload;
}

// The baseline: each request gets a view not yet taken, whatever it sees, the same ones for the same
// seed; once all are taken, no_view says so.
TEST(ExplorationPlanner, RandomNextViewsTakeEachCandidateOnceInTheSeedsOrder) {
  auto drawn = [](int seed) {
    ComponentHarness h(built_plugins(), "grasp.exploration_planner", ring8({{"next_view", std::string("random")}, {"seed", seed}}));
    std::vector<int> azimuths;
    for (int k = 0; k < 9; ++k) {
      h.push<fba::Octree>("octree", box_model(k + 1));
      h.push<fba::RegionsOfInterest>("regions", plus_x_face());
      h.run();
    }
    for (const auto& t : h.values<fba::Pose>("target")) azimuths.push_back(azimuth_deg(t));
    const auto none = find_event(h.events(), "no_view");
    EXPECT_TRUE(none.has_value());
    if (none) EXPECT_NE(none->payload.find("every one of the 8 candidate views is taken"), std::string::npos) << none->payload;
    return azimuths;
  };
  const std::vector<int> a = drawn(1);
  ASSERT_EQ(a.size(), 8u);
  EXPECT_EQ(std::set<int>(a.begin(), a.end()).size(), 8u);  // each view once
  EXPECT_EQ(drawn(1), a);
  EXPECT_NE(drawn(2), a);
  EXPECT_NE(a, (std::vector<int>{0, 45, 90, 135, 180, 225, 270, 315}));  // not simply in order
}

TEST(ExplorationPlanner, ARequestWaitsUntilEveryRequestedViewIsInTheModel) {
  ComponentHarness h(built_plugins(), "grasp.exploration_planner", ring8(), {"start"});
  h.push<std::int64_t>("start", 0);
  h.run();
  ASSERT_EQ(h.values<fba::Pose>("target").size(), 3u);
  // A model of 2 views asks before the third initial view is in: no new target yet.
  h.push<fba::Octree>("octree", box_model(2));
  h.push<fba::RegionsOfInterest>("regions", plus_x_face());
  h.run();
  EXPECT_EQ(h.values<fba::Pose>("target").size(), 3u);
  // The third view arrives: the held request is answered, never with a view already requested.
  h.push<fba::Octree>("octree", box_model(3));
  h.run();
  const auto targets = h.values<fba::Pose>("target");
  ASSERT_EQ(targets.size(), 4u);
  const int az = azimuth_deg(targets[3]);
  EXPECT_TRUE(az != 0 && az != 45 && az != 315) << az;
  // From 90 or 270 degrees only the face's nearest row is in sight, a quarter of it.
  EXPECT_TRUE(az == 90 || az == 270) << az;
}

TEST(ExplorationPlanner, ARequestWithAContactGetsAViewThatGrazesItNotTheOneFacingIt) {
  ComponentHarness h(built_plugins(), "grasp.exploration_planner", ring8());
  auto request = plus_x_face();
  request.points.push_back({Eigen::Vector3d(0.5, 0, 0), Eigen::Vector3d::UnitX(), 0});
  h.push<fba::Octree>("octree", box_model(1));
  h.push<fba::RegionsOfInterest>("regions", request);
  h.run();
  const auto targets = h.values<fba::Pose>("target");
  ASSERT_EQ(targets.size(), 1u);
  // From 0 deg the camera faces the contact and sees the whole face; from 90 or 270 deg its line of
  // sight grazes the contact, the only place a silhouette fixes the surface.
  const int az = azimuth_deg(targets[0]);
  EXPECT_TRUE(az == 90 || az == 270) << az;
  const auto chosen = find_event(h.events(), "view_chosen");
  ASSERT_TRUE(chosen.has_value());
  const auto j = nlohmann::json::parse(chosen->payload);
  EXPECT_TRUE(j.at("by_points").get<bool>()) << chosen->payload;
  EXPECT_EQ(j.at("first"), 1);
  EXPECT_EQ(j.at("points"), 1);
}

TEST(ExplorationPlanner, TheViewsAlreadyTakenCountAsGrazingLinesOfSight) {
  ComponentHarness h(built_plugins(), "grasp.exploration_planner", ring8(), {"start"});
  h.push<std::int64_t>("start", 0);
  h.push<fba::Octree>("octree", box_model(3));
  h.run();
  ASSERT_EQ(h.values<fba::Pose>("target").size(), 3u);  // azimuths 0, 45 and 315
  // A contact on the +y face: the initial view from 0 deg grazes it already, and the only other
  // grazing view of the ring, from 180 deg, is the same line of sight: no view of the ring pins it,
  // so the planner falls back to the uncertain nodes of the region.
  auto request = plus_x_face(3);
  request.points.push_back({Eigen::Vector3d(0, 0.5, 0), Eigen::Vector3d::UnitY(), 0});
  h.push<fba::RegionsOfInterest>("regions", request);
  h.run();
  ASSERT_EQ(h.values<fba::Pose>("target").size(), 4u);
  const auto chosen = find_event(h.events(), "view_chosen");
  ASSERT_TRUE(chosen.has_value());
  const auto j = nlohmann::json::parse(chosen->payload);
  EXPECT_FALSE(j.at("by_points").get<bool>()) << chosen->payload;
  EXPECT_EQ(j.at("points"), 1);
  EXPECT_NE(azimuth_deg(h.values<fba::Pose>("target")[3]), 180);
}

TEST(ExplorationPlanner, NothingUncertainLeftGivesNoViewWithTheReason) {
  ComponentHarness h(built_plugins(), "grasp.exploration_planner", ring8());
  h.push<fba::Octree>("octree", box_model(1));
  h.push<fba::RegionsOfInterest>("regions", fba::RegionsOfInterest{{Eigen::AlignedBox3d(
                                                Eigen::Vector3d::Constant(0.8), Eigen::Vector3d::Constant(0.9))}});
  h.run();
  EXPECT_TRUE(h.values<fba::Pose>("target").empty());
  const auto none = find_event(h.events(), "no_view");
  ASSERT_TRUE(none.has_value());
  EXPECT_NE(nlohmann::json::parse(none->payload).at("reason").get<std::string>().find("no uncertain node"), std::string::npos)
      << none->payload;
}

TEST(ExplorationPlanner, WithoutACentreTheRingIsAroundTheModel) {
  auto p = ring8();
  p.erase("centre");
  ComponentHarness h(built_plugins(), "grasp.exploration_planner", p);
  h.push<fba::Octree>("octree", box_model(1));
  h.push<fba::RegionsOfInterest>("regions", plus_x_face());
  h.run();
  ASSERT_EQ(h.values<fba::Pose>("target").size(), 1u);
  EXPECT_EQ(azimuth_deg(h.values<fba::Pose>("target")[0]), 0);
}

TEST(ExplorationPlanner, RecordedCandidatesAreTheImageSetsCameraPoses) {
  const std::string par = fba::test::kDinoPar;
  ComponentHarness h(built_plugins(), "grasp.exploration_planner",
                     {{"views", std::string("recorded")}, {"poses_from", par}, {"initial_views", 1}}, {"start"});
  h.push<std::int64_t>("start", 0);
  h.run();
  const auto targets = h.values<fba::Pose>("target");
  ASSERT_EQ(targets.size(), 1u);
  const auto set = fba::vision::ImageSet::load(par);
  EXPECT_LT((targets[0].world_from_frame.translation() - set[0].camera.centre_in_world()).norm(), 1e-9);
  EXPECT_LT((targets[0].world_from_frame.linear() - set[0].camera.camera_from_world.linear().transpose()).norm(), 1e-9);
}

TEST(ExplorationPlanner, BadConfigurationsAreRefusedWithTheReason) {
  EXPECT_THROW(ComponentHarness(built_plugins(), "grasp.exploration_planner", {{"views", std::string("recorded")}}), fba::ConfigError);
  EXPECT_THROW(ComponentHarness(built_plugins(), "grasp.exploration_planner",
                                {{"min_elevation_deg", 40.0}, {"max_elevation_deg", 10.0}}),
               fba::ConfigError);
  try {
    ComponentHarness h(built_plugins(), "grasp.exploration_planner", {{"views", std::string("ring")}}, {"start"});
    FAIL() << "no exception";
  } catch (const fba::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("set centre"), std::string::npos) << e.what();
  }
}

TEST(ExplorationPlanner, ARequestFromAModelWithoutTheLastViewIsDropped) {
  ComponentHarness h(built_plugins(), "grasp.exploration_planner", ring8(), {"start"});
  h.push<std::int64_t>("start", 0);
  h.push<fba::Octree>("octree", box_model(3));
  h.run();
  ASSERT_EQ(h.values<fba::Pose>("target").size(), 3u);
  // Synthesis answered a 2-view model late, after the model of 3 views had arrived: not a request
  // about the newest model, so no view is chosen on it, now or later.
  h.push<fba::RegionsOfInterest>("regions", plus_x_face(2));
  h.run();
  h.push<fba::Octree>("octree", box_model(3));
  h.run();
  EXPECT_EQ(h.values<fba::Pose>("target").size(), 3u);
  // Its answer about the 3-view model is one.
  h.push<fba::RegionsOfInterest>("regions", plus_x_face(3));
  h.run();
  EXPECT_EQ(h.values<fba::Pose>("target").size(), 4u);
}
