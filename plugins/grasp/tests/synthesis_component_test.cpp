// grasp.synthesis through the component harness, on voxelised models of known shapes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <set>
#include <string>

#include <nlohmann/json.hpp>

#include <fba/task_config.hpp>
#include <fba/testing.hpp>
#include <fba/types/grasp.hpp>
#include <fba/types/octree.hpp>
#include <fba/types/regions_of_interest.hpp>
#include <fba/types/silhouette.hpp>

#include "fba/grasp/grasp_json.hpp"
#include "support/built_plugins.hpp"
#include "support/events.hpp"
#include "support/voxel_shapes.hpp"

namespace {

using fba::testing::ComponentHarness;
namespace gt = fba::grasp::test;

using fba::test::built_plugins;
using fba::test::named;

const Eigen::AlignedBox3d kCube(Eigen::Vector3d::Constant(-0.08), Eigen::Vector3d::Constant(0.08));
constexpr double kRadius = 0.035;

// An upright cylinder (radius 35 mm, 120 mm tall) resolved to depth 6 (2.5 mm leaves) where
// leaf_depth allows.
fba::Octree cylinder(int views, std::function<int(const Eigen::Vector3d&)> leaf_depth = {}) {
  return gt::voxelise(gt::cylinder_sdf(kRadius, -0.06, 0.12), kCube, 6, std::move(leaf_depth), views);
}

TEST(GraspSynthesisComponent, SelectsAGraspOnACylinderWithContactsOnItsSide) {
  ComponentHarness h(built_plugins(), "grasp.synthesis");
  EXPECT_EQ(h.stage(), "visual_analysis");
  h.push<fba::Octree>("octree", cylinder(8));
  h.run();
  const auto grasps = h.values<fba::Grasp>("grasp");
  ASSERT_EQ(grasps.size(), 1u) << (named(h.events(), "planning_performed").empty() ? "" : named(h.events(), "planning_performed")[0].payload);
  const fba::Grasp& g = grasps[0];
  const double edge = 0.16 / 64;
  for (const auto& c : g.contacts) {
    EXPECT_NEAR(std::hypot(c.position.x(), c.position.y()), kRadius, 2 * edge) << c.position.transpose();
    EXPECT_LT(std::abs(c.position.z()), 0.06 - edge);  // on the side, not a cap's rim
    // Inward: towards the axis.
    EXPECT_LT(c.normal.dot(Eigen::Vector3d(c.position.x(), c.position.y(), 0).normalized()), -0.9);
  }
  // Of the reliable candidates the most stable on the model is selected, not the most symmetric one.
  EXPECT_GT(g.scores.symmetry, 0.6);
  EXPECT_GE(g.scores.total, 0.45);  // the default threshold
  EXPECT_EQ(g.views.size(), 8u);
  const auto selected = named(h.events(), "grasp_selected");
  ASSERT_EQ(selected.size(), 1u);
  const fba::Grasp from_event = fba::grasp::grasp_from_json(nlohmann::json::parse(selected[0].payload), "grasp_selected");
  EXPECT_EQ(from_event.contacts[0].position, g.contacts[0].position);
  // Its force-closure quality beside it (the run's last line says it): a selected grasp is force
  // closure on the model, so its epsilon there is positive.
  const nlohmann::json payload = nlohmann::json::parse(selected[0].payload);
  ASSERT_TRUE(payload.contains("model_epsilon") && payload["model_epsilon"].is_number()) << payload;
  EXPECT_GT(payload["model_epsilon"].get<double>(), 0.0) << payload;
  EXPECT_EQ(h.stage(), "grasp_synthesis");
  EXPECT_TRUE(h.values<fba::RegionsOfInterest>("regions").empty());

  // Selecting ends the work: a later model changes nothing.
  h.push<fba::Octree>("octree", cylinder(9));
  h.run();
  EXPECT_EQ(h.values<fba::Grasp>("grasp").size(), 1u);
  EXPECT_EQ(named(h.events(), "grasp_selected").size(), 1u);
  EXPECT_TRUE(h.failure().empty()) << h.failure();
}

// The scores of the grasp selected on the cylinder seen from 8 views, with `params`.
fba::GraspScores scores_on_cylinder(const fba::testing::Params& params) {
  ComponentHarness h(built_plugins(), "grasp.synthesis", params);
  h.push<fba::Octree>("octree", cylinder(8));
  h.run();
  const auto grasps = h.values<fba::Grasp>("grasp");
  if (grasps.size() != 1) ADD_FAILURE() << grasps.size() << " grasps selected, not one";
  return grasps.empty() ? fba::GraspScores{} : grasps[0].scores;
}

// S4 on the cylinder's convex side follows curvature_scale: its mean curvature 1/(2r) = 14.3 1/m
// scores 0.5 - 0.5 * 14.3 / scale, 0.21 at the default 25 and 0.36 at 50, under a flat face's 0.5
// (the model's curvature, a little less than the cylinder's where the selected contacts are).
TEST(GraspSynthesisComponent, TheCurvatureScoreFollowsCurvatureScale) {
  const double s4_25 = scores_on_cylinder({}).curvature, s4_50 = scores_on_cylinder({{"curvature_scale", 50.0}}).curvature;
  EXPECT_GT(s4_25, 0.5 - 0.5 / (2 * kRadius) / 25 - 0.02);
  EXPECT_GT(s4_50, 0.5 - 0.5 / (2 * kRadius) / 50 - 0.02);
  EXPECT_LT(s4_50, 0.5);
  EXPECT_GT(s4_50, s4_25 + 0.1);
  EXPECT_THROW(ComponentHarness(built_plugins(), "grasp.synthesis", {{"curvature_scale", 0}}), fba::ConfigError);
}

// S3 follows safety_reference: on the cylinder's side, 12 cm tall, the selected contacts lie
// centimetres inside their region, past the default reference (the finger's width, 2 cm): S3 is 1;
// against a reference of 20 cm, more than half the side's height, S3 is a fraction.
TEST(GraspSynthesisComponent, TheSafetyScoreFollowsSafetyReference) {
  EXPECT_DOUBLE_EQ(scores_on_cylinder({}).safety_margin, 1.0);
  const double s3_20cm = scores_on_cylinder({{"safety_reference", 0.2}}).safety_margin;
  EXPECT_GT(s3_20cm, 0.0);
  EXPECT_LT(s3_20cm, 0.5);
}

// A floor on S1 no contacts on the voxelised cylinder reach leaves every candidate out; the
// reason at the last view counts them.
TEST(GraspSynthesisComponent, AFloorOnSymmetryNoCandidateReachesIsTheReasonGiven) {
  ComponentHarness h(built_plugins(), "grasp.synthesis", {{"min_symmetry", 0.999}, {"max_views", 8}});
  h.push<fba::Octree>("octree", cylinder(8));
  h.run();
  EXPECT_TRUE(h.values<fba::Grasp>("grasp").empty());
  const auto failed = named(h.events(), "grasp_synthesis_failed");
  ASSERT_EQ(failed.size(), 1u);
  EXPECT_NE(failed[0].payload.find("with S1 under min_symmetry"), std::string::npos) << failed[0].payload;
  EXPECT_THROW(ComponentHarness(built_plugins(), "grasp.synthesis", {{"min_symmetry", 1.5}}), fba::ConfigError);
}

TEST(GraspSynthesisComponent, AnEmptyModelFailsWithTheReason) {
  ComponentHarness h(built_plugins(), "grasp.synthesis");
  fba::Octree empty;
  empty.bounds = kCube;
  empty.max_depth = 6;
  empty.views = 3;
  empty.root.set_state(fba::NodeState::Empty);
  h.push<fba::Octree>("octree", empty);
  h.run();
  const auto failed = named(h.events(), "grasp_synthesis_failed");
  ASSERT_EQ(failed.size(), 1u);
  EXPECT_EQ(failed[0].payload.rfind("the model is empty after 3 views", 0), 0u) << failed[0].payload;
  EXPECT_TRUE(h.values<fba::Grasp>("grasp").empty());
  EXPECT_TRUE(h.failure().empty()) << h.failure();  // a reason for the task's rules, not a crash
}

// A table below the whole model (a wrong table_z, or a root box that stops short of the table):
// nothing rests on it, and the reason names the table.
TEST(GraspSynthesisComponent, AModelNotJoinedToTheTableFailsNamingTheTable) {
  ComponentHarness h(built_plugins(), "grasp.synthesis", {{"table_z", std::vector<double>{-0.5}}});
  h.push<fba::Octree>("octree", cylinder(3));
  h.run();
  const auto failed = named(h.events(), "grasp_synthesis_failed");
  ASSERT_EQ(failed.size(), 1u);
  EXPECT_EQ(failed[0].payload.rfind("none of the model's ", 0), 0u) << failed[0].payload;
  EXPECT_NE(failed[0].payload.find("views is joined to the table at z = -0.500"), std::string::npos) << failed[0].payload;
  EXPECT_TRUE(h.values<fba::Grasp>("grasp").empty());
  EXPECT_TRUE(h.failure().empty()) << h.failure();
}

// An object outside the workspace is seen through it: the views' cones end on the root box's
// faces, away from the table. The reason names the faces and the workspace.
TEST(GraspSynthesisComponent, AModelReachingTheWorkspacesBoundsAwayFromTheTableSaysTheObjectMayBeOutsideIt) {
  ComponentHarness h(built_plugins(), "grasp.synthesis", {{"table_z", std::vector<double>{-0.08}}});
  h.push<fba::Octree>("octree", gt::voxelise(gt::box_sdf({0.07, 0, 0.03}, {0.04, 0.04, 0.04}), kCube, 5, {}, 3));
  h.run();
  const auto failed = named(h.events(), "grasp_synthesis_failed");
  ASSERT_EQ(failed.size(), 1u);
  EXPECT_EQ(failed[0].payload.rfind("the carved model reaches the workspace's bounds at x = 0.080 (the carver's root box [-0.080, -0.080, "
                                    "-0.080, 0.080, 0.080, 0.080]), and none of its ",
                                    0),
            0u)
      << failed[0].payload;
  EXPECT_NE(failed[0].payload.find("after 3 views is joined to the table at z = -0.080: the object may be larger than or outside the "
                                   "workspace"),
            std::string::npos)
      << failed[0].payload;
  EXPECT_TRUE(h.failure().empty()) << h.failure();
}

TEST(GraspSynthesisComponent, AModelWithoutATreeYetIsWaitedFor) {
  ComponentHarness h(built_plugins(), "grasp.synthesis");
  fba::Octree none;
  none.node_count = 0;
  h.push<fba::Octree>("octree", none);
  h.run();
  EXPECT_TRUE(h.events().empty());
  EXPECT_EQ(h.stage(), "visual_analysis");
}

// Resolved only to depth 3 of 6 everywhere: every candidate is uncertain, so the component asks
// for detail and a new view where its candidates' regions are.
TEST(GraspSynthesisComponent, AnUnresolvedModelEmitsRegionsAndPlansAView) {
  ComponentHarness h(built_plugins(), "grasp.synthesis");
  h.push<fba::Octree>("octree", cylinder(3, [](const Eigen::Vector3d&) { return 4; }));
  h.run();
  EXPECT_TRUE(h.values<fba::Grasp>("grasp").empty());
  const auto regions = h.values<fba::RegionsOfInterest>("regions");
  ASSERT_EQ(regions.size(), 1u);
  ASSERT_FALSE(regions[0].boxes.empty());
  for (const auto& b : regions[0].boxes) EXPECT_TRUE(kCube.contains(b.center())) << b.center().transpose();
  const auto planned = named(h.events(), "planning_performed");
  ASSERT_EQ(planned.size(), 1u);
  const auto j = nlohmann::json::parse(planned[0].payload);
  EXPECT_EQ(j.at("views"), 3);
  EXPECT_GT(j.at("samples").get<int>(), 0);
  EXPECT_EQ(j.at("regions_requested").get<std::size_t>(), regions[0].boxes.size());
  EXPECT_EQ(h.stage(), "exploration_movement");

  // The resolved model then yields a grasp.
  h.push<fba::Octree>("octree", cylinder(4));
  h.run();
  EXPECT_EQ(h.values<fba::Grasp>("grasp").size(), 1u);
  EXPECT_EQ(h.stage(), "grasp_synthesis");
}

// After each analysis, before a grasp is selected too, synthesis shows its first candidates for a
// live view, best first: a few of those it found, the one it then selects among them.
TEST(GraspSynthesisComponent, EachAnalysisShowsItsFirstCandidates) {
  ComponentHarness h(built_plugins(), "grasp.synthesis");
  h.push<fba::Octree>("octree", cylinder(3, [](const Eigen::Vector3d&) { return 4; }));
  h.run();
  ASSERT_TRUE(h.values<fba::Grasp>("grasp").empty());
  const auto planned = nlohmann::json::parse(named(h.events(), "planning_performed").at(0).payload);
  auto shown = h.values<fba::GraspCandidates>("candidates");
  ASSERT_EQ(shown.size(), 1u);
  EXPECT_EQ(shown[0].views, 3);
  EXPECT_EQ(shown[0].total, planned.at("candidates").get<std::size_t>());
  EXPECT_FALSE(shown[0].candidates.empty());
  EXPECT_LT(shown[0].candidates.size(), shown[0].total) << "a few of them";

  h.push<fba::Octree>("octree", cylinder(4));
  h.run();
  const auto grasps = h.values<fba::Grasp>("grasp");
  ASSERT_EQ(grasps.size(), 1u);
  shown = h.values<fba::GraspCandidates>("candidates");
  ASSERT_EQ(shown.size(), 2u);
  EXPECT_EQ(shown[1].views, 4);
  const auto same = [&](const fba::GraspCandidates::Candidate& c) {
    for (std::size_t i = 0; i < 3; ++i)
      if (c.grasp.contacts[i].position != grasps[0].contacts[i].position) return false;
    return true;
  };
  EXPECT_TRUE(std::any_of(shown[1].candidates.begin(), shown[1].candidates.end(), same)) << "the selected grasp is among them";
}

// A model resolved only to depth 4 of 6: its partial leaves are unresolved, the full ones beside
// empty space are resolved at any depth. No candidate has all the surface under its fingers
// resolved; after the last view synthesis settles for one whose contacts are.
TEST(GraspSynthesisComponent, AfterMaxViewsItSettlesForACandidateWhoseContactsAreResolved) {
  ComponentHarness h(built_plugins(), "grasp.synthesis", {{"max_views", 4}});
  auto coarse = [](const Eigen::Vector3d&) { return 4; };
  h.push<fba::Octree>("octree", cylinder(3, coarse));
  h.run();
  EXPECT_EQ(named(h.events(), "planning_performed").size(), 1u);
  EXPECT_TRUE(h.values<fba::Grasp>("grasp").empty());
  h.push<fba::Octree>("octree", cylinder(4, coarse));
  h.run();
  EXPECT_TRUE(named(h.events(), "grasp_synthesis_failed").empty());
  EXPECT_EQ(h.values<fba::Grasp>("grasp").size(), 1u);
}

// The same model with contacts_views 3: a candidate whose contacts are resolved is taken from the
// third view on, long before max_views (without it, the third view asks for more: the test above).
TEST(GraspSynthesisComponent, WithContactsViewsACandidateOnResolvedContactsIsTakenFromThatView) {
  ComponentHarness h(built_plugins(), "grasp.synthesis", {{"max_views", 10}, {"contacts_views", 3}});
  auto coarse = [](const Eigen::Vector3d&) { return 4; };
  h.push<fba::Octree>("octree", cylinder(3, coarse));
  h.run();
  EXPECT_TRUE(named(h.events(), "planning_performed").empty());
  EXPECT_EQ(h.values<fba::Grasp>("grasp").size(), 1u);
}

// The cylinder's middle band left at depth 5 of 6 (unresolved), its ends resolved: the steadiest
// grasps, around the middle, are not resolved yet (epsilon 0.11 on the model against 0.04 for the
// best resolved one, near an end). Before the last view the resolved one waits for them (the
// default stability_share, 0.5); with stability_share 0 it is taken at once; after the last view
// it is the best there is.
TEST(GraspSynthesisComponent, AResolvedCandidateMuchLessStableThanTheBestWaitsUntilTheLastView) {
  auto middle_unresolved = [](const Eigen::Vector3d& x) { return std::abs(x.z()) < 0.025 ? 5 : 6; };
  {
    ComponentHarness h(built_plugins(), "grasp.synthesis", {{"stability_share", 0.0}});
    h.push<fba::Octree>("octree", cylinder(3, middle_unresolved));
    h.run();
    const auto grasps = h.values<fba::Grasp>("grasp");
    ASSERT_EQ(grasps.size(), 1u);
    for (const auto& c : grasps[0].contacts) EXPECT_GT(std::abs(c.position.z()), 0.025) << c.position.transpose();
  }
  ComponentHarness h(built_plugins(), "grasp.synthesis", {{"max_views", 4}});
  h.push<fba::Octree>("octree", cylinder(3, middle_unresolved));
  h.run();
  EXPECT_TRUE(h.values<fba::Grasp>("grasp").empty());
  EXPECT_EQ(named(h.events(), "planning_performed").size(), 1u);
  // The request is the unresolved middle, where the better candidates are.
  const auto regions = h.values<fba::RegionsOfInterest>("regions");
  ASSERT_EQ(regions.size(), 1u);
  ASSERT_FALSE(regions[0].boxes.empty());
  for (const auto& b : regions[0].boxes) EXPECT_LT(b.min().z(), 0.025) << b.min().transpose();
  h.push<fba::Octree>("octree", cylinder(4, middle_unresolved));
  h.run();
  EXPECT_TRUE(named(h.events(), "grasp_synthesis_failed").empty());
  const auto grasps = h.values<fba::Grasp>("grasp");
  ASSERT_EQ(grasps.size(), 1u);
  for (const auto& c : grasps[0].contacts) EXPECT_GT(std::abs(c.position.z()), 0.025) << c.position.transpose();
}

// With rim_deg, a view whose silhouette has no rim pins nothing: no contact is ever resolved, and
// after max_views synthesis gives up saying so, with the best candidate's total and criteria.
TEST(GraspSynthesisComponent, GivesUpAfterMaxViewsSayingNoCandidateIsOnResolvedSurface) {
  ComponentHarness h(built_plugins(), "grasp.synthesis", {{"max_views", 4}, {"rim_deg", 15.0}}, {"silhouette"});
  auto frame = std::make_shared<fba::Frame>();
  frame->has_pose = true;
  fba::Silhouette silhouette;
  silhouette.frame = frame;
  h.push<fba::Silhouette>("silhouette", silhouette);
  h.push<fba::Octree>("octree", cylinder(3));
  h.run();
  EXPECT_EQ(named(h.events(), "planning_performed").size(), 1u);
  EXPECT_TRUE(named(h.events(), "grasp_synthesis_failed").empty());
  h.push<fba::Octree>("octree", cylinder(4));
  h.run();
  const auto failed = named(h.events(), "grasp_synthesis_failed");
  ASSERT_EQ(failed.size(), 1u);
  const std::string& why = failed[0].payload;
  EXPECT_EQ(why.rfind("no reliable grasp after 4 views: none of the ", 0), 0u) << why;
  EXPECT_NE(why.find(" candidates has its contacts and the surface around them resolved (pinned by two views' rims), nor a "
                     "reliable one its contacts; the best, of total "),
            std::string::npos)
      << why;
  for (const char* part : {"(S1 symmetry ", ", S3 safety margin ", ", S4 curvature ",
                           "touches a part of the model not yet resolved (threshold 0.450)"})
    EXPECT_NE(why.find(part), std::string::npos) << part << " in " << why;
  EXPECT_TRUE(h.values<fba::Grasp>("grasp").empty());
  // Then it ignores input.
  h.push<fba::Octree>("octree", cylinder(5));
  h.run();
  EXPECT_TRUE(h.values<fba::Grasp>("grasp").empty());
}

TEST(GraspSynthesisComponent, AThresholdNoCandidateReachesFailsAtMaxViews) {
  ComponentHarness h(built_plugins(), "grasp.synthesis", {{"max_views", 8}, {"threshold", 1.0}});
  h.push<fba::Octree>("octree", cylinder(8));
  h.run();
  ASSERT_EQ(named(h.events(), "grasp_synthesis_failed").size(), 1u);
  EXPECT_TRUE(h.values<fba::Grasp>("grasp").empty());
}

// A hand that opens to 3 cm cannot take a 7 cm cylinder: no candidate, so it asks for the whole
// model (more views may carve it smaller) until max_views, then names the cause.
TEST(GraspSynthesisComponent, NoCandidateTheHandCanReachAsksForTheWholeModelThenFails) {
  ComponentHarness h(built_plugins(), "grasp.synthesis",
                     {{"aperture_max", 0.03}, {"spread_max", 0.03}, {"spread_min", 0.02}, {"max_views", 9}});
  h.push<fba::Octree>("octree", cylinder(8));
  h.run();
  const auto regions = h.values<fba::RegionsOfInterest>("regions");
  ASSERT_EQ(regions.size(), 1u);
  ASSERT_EQ(regions[0].boxes.size(), 1u);
  const auto& box = regions[0].boxes[0];
  EXPECT_NEAR(box.min().x(), -kRadius, 0.005);
  EXPECT_NEAR(box.max().z(), 0.06, 0.005);
  const auto j = nlohmann::json::parse(named(h.events(), "planning_performed").at(0).payload);
  EXPECT_EQ(j.at("candidates"), 0);
  EXPECT_EQ(j.at("regions_requested"), 1);
  h.push<fba::Octree>("octree", cylinder(9));
  h.run();
  const auto failed = named(h.events(), "grasp_synthesis_failed");
  ASSERT_EQ(failed.size(), 1u);
  // What removed the candidates, not a best total of nothing.
  EXPECT_EQ(failed[0].payload, "no reliable grasp after 9 views: no candidate the hand can reach") << failed[0].payload;
}

// With rim_deg, one view pins nothing down (a silhouette fixes the surface only where two grazing
// lines of sight cross): no grasp yet, and the request names the surface under the best candidates'
// fingers, one group per candidate, for the planner to graze.
TEST(GraspSynthesisComponent, WithOneViewTheRequestNamesTheUnpinnedSurfaceUnderTheBestCandidates) {
  ComponentHarness h(built_plugins(), "grasp.synthesis", {{"rim_deg", 15.0}}, {"silhouette"});
  auto frame = std::make_shared<fba::Frame>();
  frame->has_pose = true;
  frame->camera.camera_from_world = Eigen::Translation3d(-0.5, 0, 0);  // the camera centre at (0.5, 0, 0)
  fba::Silhouette silhouette;
  silhouette.frame = frame;
  h.push<fba::Silhouette>("silhouette", silhouette);
  h.push<fba::Octree>("octree", cylinder(1));
  h.run();
  EXPECT_TRUE(h.values<fba::Grasp>("grasp").empty());
  const auto regions = h.values<fba::RegionsOfInterest>("regions");
  ASSERT_EQ(regions.size(), 1u);
  const auto& roi = regions[0];
  ASSERT_FALSE(roi.points.empty());
  EXPECT_EQ(roi.rim_deg, 15.0);
  EXPECT_EQ(roi.rim_separation_deg, 20.0);
  const double edge = 0.16 / 64;
  std::set<int> groups;
  for (const auto& p : roi.points) {
    groups.insert(p.group);
    EXPECT_NEAR(p.normal.norm(), 1.0, 1e-9);
    // On the cylinder's side, facing out.
    EXPECT_NEAR(std::hypot(p.position.x(), p.position.y()), kRadius, 2 * edge) << p.position.transpose();
    EXPECT_GT(p.normal.dot(Eigen::Vector3d(p.position.x(), p.position.y(), 0).normalized()), 0.8);
  }
  EXPECT_GE(*groups.begin(), 0);
  EXPECT_LT(*groups.rbegin(), 5);  // at most the five best candidates
  const auto j = nlohmann::json::parse(named(h.events(), "planning_performed").at(0).payload);
  EXPECT_EQ(j.at("points_requested").get<std::size_t>(), roi.points.size());
  EXPECT_TRUE(j.at("best").at("uncertain").get<bool>());
}

TEST(GraspSynthesisComponent, AnInconsistentHandIsRefusedWhenLoaded) {
  EXPECT_THROW(ComponentHarness(built_plugins(), "grasp.synthesis", {{"aperture_min", 0.2}, {"aperture_max", 0.1}}), fba::ConfigError);
  EXPECT_THROW(ComponentHarness(built_plugins(), "grasp.synthesis", {{"finger_width", 0.2}}), fba::ConfigError);  // > spread_max
  EXPECT_THROW(ComponentHarness(built_plugins(), "grasp.synthesis",
                                {{"weight_symmetry", 0}, {"weight_safety", 0}, {"weight_curvature", 0}}),
               fba::ConfigError);
}

}  // namespace
