// grasp.synthesis with the arm's joints: it passes over the candidates the arm cannot reach from
// where it stands (the reach planner's reachable(), with motion.reach_planner's parameters), counts
// them by refusal, says `unreachable` when none is reachable and asks for views; without joints it
// selects as before. Its palm sits where motion.reach_planner's does (the robot's flange_to_palm).
// Scenes: boxes carved exactly in the task's workspace at depth 6, the arm at sim.arm's initial
// pose (the camera 0.35 m from the origin, 60 degrees up on the arm's side).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <fba/testing.hpp>

#include "reach_scene.hpp"

FBA_COMPONENT(fba::grasp::test::reach::SceneSensor);

namespace reach = fba::grasp::test::reach;
using fba::motion::test::home;

namespace {

const fba::motion::ReachPlanner& reach_planner() {
  static const fba::motion::ReachPlanner p(fba::motion::test::arm_urdf());
  return p;
}

bool same_contacts(const fba::Grasp& a, const fba::Grasp& b) {
  for (int i = 0; i < 3; ++i)
    if (!a.contacts[i].position.isApprox(b.contacts[i].position, 1e-12)) return false;
  return true;
}

}  // namespace

// Synthesis's own table check off (no table_z): the best candidate takes the box low from the
// side, its palm below the table. The arm's planner knows the table: synthesis passes over that
// one and those like it, and selects a worse one the arm reaches.
TEST(GraspSynthesisReach, TheBestCandidateWhosePalmWouldGoIntoTheTableIsPassedOverForAReachableOne) {
  const std::vector<double> box = reach::standing({0.06, 0.06, 0.06});
  const std::string margin = "edge_margin_mm: 0, level_tilt_deg: 0, level_squeeze_deg: 0";  // the scene's best candidate lies near an edge of the box, from the side
  const reach::Outcome before = reach::synthesise(box, {}, margin);
  ASSERT_EQ(before.grasps.size(), 1u) << before.run.reason;
  const fba::motion::ReachPlan refused = reach_planner().reachable(before.grasps[0], reach::box_model_of(box), home());
  ASSERT_EQ(refused.refusal, fba::motion::Refusal::Table) << refused.why;
  ASSERT_EQ(refused.why, "the pregrasp puts the palm into the table");

  const reach::Outcome after = reach::synthesise(box, home(), margin);
  ASSERT_EQ(after.grasps.size(), 1u) << after.run.reason;
  EXPECT_FALSE(same_contacts(after.grasps[0], before.grasps[0]));
  const fba::motion::ReachPlan plan = reach_planner().plan(after.grasps[0], reach::box_model_of(box), home());
  EXPECT_TRUE(plan.ok) << plan.why;  // the path too, which synthesis does not search
  EXPECT_TRUE(after.events("unreachable").empty());

  const auto report = nlohmann::json::parse(after.result("reach"));
  EXPECT_EQ(report["views"], 8);
  ASSERT_TRUE(report["passed_over"].contains("table")) << report;
  EXPECT_GE(report["passed_over"]["table"]["count"], 1);
  EXPECT_EQ(report["passed_over"]["table"]["example"], "the pregrasp puts the palm into the table");
  // Best first, until one is reachable: every candidate checked but the selected one was passed over.
  EXPECT_EQ(report["passed_over_count"].get<int>() + 1, report["checked"].get<int>()) << report;
  EXPECT_TRUE(report["seconds"].is_number()) << report;  // the check's time is reported (its size is a benchmark's)
}

// A tall box beyond the object's centre from the arm's base: the best candidate comes at it from
// the far side, where the arm does not reach (no IK solution for the pregrasp); the next one it
// reaches.
TEST(GraspSynthesisReach, TheBestCandidateBehindTheObjectBeyondTheArmsReachIsPassedOver) {
  const std::vector<double> box = reach::standing({0.06, 0.06, 0.14}, 0.08);
  // The box's lowest leaves reach down to the table. The scene's far-side grasp is one synthesis's
  // approximate hand keeps clear of the table (the robot's hand, with its clearance, refuses it).
  const std::string table = "table_z: [0.001], edge_margin_mm: 0, robot_hand: false, level_tilt_deg: 0, level_squeeze_deg: 0";
  const reach::Outcome before = reach::synthesise(box, {}, table);
  ASSERT_EQ(before.grasps.size(), 1u) << before.run.reason;
  EXPECT_LT(before.grasps[0].approach.x(), -0.9);  // from the far side, towards the arm
  EXPECT_EQ(reach_planner().reachable(before.grasps[0], reach::box_model_of(box), home()).refusal, fba::motion::Refusal::Ik);

  const reach::Outcome after = reach::synthesise(box, home(), table);
  ASSERT_EQ(after.grasps.size(), 1u) << after.run.reason;
  EXPECT_FALSE(same_contacts(after.grasps[0], before.grasps[0]));
  EXPECT_TRUE(reach_planner().reachable(after.grasps[0], reach::box_model_of(box), home()).ok);
  const auto report = nlohmann::json::parse(after.result("reach"));
  ASSERT_TRUE(report["passed_over"].contains("ik")) << report;
  EXPECT_EQ(report["passed_over"]["ik"]["example"].get<std::string>().rfind("no IK solution within the joint limits for the pregrasp at (", 0),
            0u)
      << report;

  // One check as far as the inverse kinematics per model: the best candidate's spends it, and the
  // others are left for the next model, neither selected nor passed over.
  const reach::Outcome one = reach::synthesise(box, home(), table + ", reach_checks: 1");
  EXPECT_TRUE(one.grasps.empty());
  ASSERT_EQ(one.events("unreachable").size(), 1u);
  const auto payload = nlohmann::json::parse(one.events("unreachable")[0].payload);
  EXPECT_EQ(payload["checked"], 1);
  EXPECT_EQ(payload["passed_over"]["ik"]["count"], 1);
  EXPECT_EQ(payload["unchecked"].get<int>() + 1, payload["candidates"].get<int>()) << payload;
  EXPECT_EQ(one.regions.size(), 1u);
}

// A flat box: every candidate's fingers would reach into the table. Synthesis says `unreachable`
// with the counts and asks for views as when none is reliable; after the last view it gives up
// with the counts. (With synthesis's approximate hand, which takes no grasp as a fingertip pinch:
// the robot's hand would pinch this box from above.)
TEST(GraspSynthesisReach, WhenNoCandidateIsReachableItSaysSoAndAsksForViews) {
  const std::vector<double> flat = reach::standing({0.06, 0.06, 0.04});
  const std::string table = "table_z: [0.001], robot_hand: false";
  ASSERT_EQ(reach::synthesise(flat, {}, table).regions.size(), 1u);  // without the arm: none reliable, views asked for too

  const reach::Outcome o = reach::synthesise(flat, home(), table);
  EXPECT_TRUE(o.grasps.empty());
  const auto unreachable = o.events("unreachable");
  ASSERT_EQ(unreachable.size(), 1u);
  const auto payload = nlohmann::json::parse(unreachable[0].payload);
  EXPECT_EQ(payload["views"], 8);
  EXPECT_GT(payload["candidates"], 0);
  EXPECT_EQ(payload["checked"], payload["candidates"]);
  ASSERT_TRUE(payload["passed_over"].contains("table")) << payload;
  EXPECT_EQ(payload["passed_over"]["table"]["count"], payload["candidates"]) << payload;
  EXPECT_EQ(payload["passed_over"]["table"]["example"].get<std::string>().rfind("the grasp puts the ", 0), 0u) << payload;
  // Views asked for: the regions, and planning_performed with the counts.
  ASSERT_EQ(o.regions.size(), 1u);
  EXPECT_FALSE(o.regions[0].boxes.empty());
  const auto planning = o.events("planning_performed");
  ASSERT_EQ(planning.size(), 1u);
  EXPECT_EQ(nlohmann::json::parse(planning[0].payload)["reach"]["passed_over"], payload["passed_over"]);
  EXPECT_EQ(nlohmann::json::parse(o.result("reach"))["passed_over"], payload["passed_over"]);

  // The last view: it gives up, saying why with the counts.
  const reach::Outcome last = reach::synthesise(flat, home(), table + ", max_views: 8");
  const auto failed = last.events("grasp_synthesis_failed");
  ASSERT_EQ(failed.size(), 1u);
  const std::string n = std::to_string(payload["candidates"].get<int>());
  EXPECT_EQ(failed[0].payload.rfind("no grasp the arm can reach after 8 views: none of the " + n +
                                        " candidates is reachable by the arm; passed over: " + n + " (table " + n +
                                        ", e.g. the grasp puts the ",
                                    0),
            0u)
      << failed[0].payload;
  EXPECT_EQ(last.events("unreachable").size(), 1u);
}

// At sim.arm's initial pose the open hand's fingers stand in a tall box: the arm backs out of the
// box, or, when it may not (max_backout 0), no candidate the arm reaches opens its hand around the
// box, and the best is selected all the same, the result saying the start is refused.
TEST(GraspSynthesisReach, AStartInTheModelThatNoCandidateClearsIsReportedForTheGraspSelected) {
  const std::vector<double> tall = reach::standing({0.06, 0.12, 0.20});
  const std::string table = "table_z: [0.001]";
  const reach::Outcome backs_out = reach::synthesise(tall, home(), table);
  ASSERT_EQ(backs_out.grasps.size(), 1u) << backs_out.run.reason;
  EXPECT_EQ(nlohmann::json::parse(backs_out.result("reach"))["start"], "clear");

  const reach::Outcome stuck = reach::synthesise(tall, home(), table + ", max_backout: 0");
  ASSERT_EQ(stuck.grasps.size(), 1u) << stuck.run.reason;
  EXPECT_TRUE(same_contacts(stuck.grasps[0], backs_out.grasps[0]));
  const auto report = nlohmann::json::parse(stuck.result("reach"));
  EXPECT_FALSE(report["passed_over"].contains("start")) << report;
  EXPECT_EQ(report["start"]["refusal"], "start") << report;
  EXPECT_EQ(report["start"]["reason"].get<std::string>().rfind("the current joints collide, with the hand open for the pregrasp: ", 0), 0u)
      << report;
  EXPECT_NE(report["start"]["reason"].get<std::string>().find(" touches the model at ("), std::string::npos) << report;
}

// Where the arm stands the open hand's fingers reach into a box 20 cm tall, and it may not back
// out (max_backout 0): the best candidate, across the box's 6 cm, opens the hand too little to
// clear it, but one across its 9 cm opens it wider, around the box, and the arm starts for that
// one. A refusal at the start is the candidate's, not every candidate's: synthesis
// selects the one the arm starts for, and the planner plans it.
TEST(GraspSynthesisReach, ACandidateTheArmCannotStartForIsPassedOverForOneWhoseOpenHandClears) {
  const std::vector<double> box = reach::standing({0.06, 0.09, 0.20}, -0.03);
  const reach::Outcome o = reach::synthesise(box, home(), "table_z: [0.001], max_backout: 0");
  ASSERT_EQ(o.grasps.size(), 1u) << o.run.reason;
  fba::motion::ReachParams stuck;
  stuck.max_backout = 0;
  const fba::motion::ReachPlanner planner(fba::motion::test::arm_urdf(), stuck);
  const fba::Octree model = reach::box_model_of(box);
  ASSERT_EQ(o.candidates.size(), 1u);
  const auto& first = o.candidates[0].candidates.front();  // the best candidate, reliable and reachable but for the start
  ASSERT_TRUE(first.reliable && !first.passed_over);
  EXPECT_FALSE(same_contacts(first.grasp, o.grasps[0]));
  const fba::motion::ReachPlan best = planner.plan(first.grasp, model, home());
  ASSERT_EQ(best.refusal, fba::motion::Refusal::Start) << best.why;
  const fba::motion::ReachPlan selected = planner.plan(o.grasps[0], model, home());
  EXPECT_TRUE(selected.ok) << selected.why;
  EXPECT_GT(selected.opening, best.opening);
  EXPECT_EQ(nlohmann::json::parse(o.result("reach"))["start"], "clear");
}

// Without a joint state (the input not wired, or wired with none arrived yet) nothing changes: the
// same grasp as before, and no reach result.
TEST(GraspSynthesisReach, WithoutAJointStateTheSameGraspIsSelectedAsBefore) {
  const std::vector<double> box = reach::standing({0.06, 0.06, 0.06});
  const reach::Outcome unwired = reach::synthesise(box, {});
  const reach::Outcome waiting = reach::synthesise(box, {}, "", true);
  ASSERT_EQ(unwired.grasps.size(), 1u);
  ASSERT_EQ(waiting.grasps.size(), 1u);
  EXPECT_TRUE(same_contacts(unwired.grasps[0], waiting.grasps[0]));
  EXPECT_EQ(unwired.grasps[0].approach, waiting.grasps[0].approach);
  EXPECT_EQ(unwired.result("reach"), "");
  EXPECT_EQ(waiting.result("reach"), "");
}

// The reach parameters synthesis checks with are motion.reach_planner's: the same names, defaults,
// ranges and docs, declared once (fba/motion/reach_parameters.hpp, with the robot's:
// robot_parameters.hpp).
TEST(GraspSynthesisReach, ItsReachParametersAreTheReachPlannersOwn) {
  const auto synthesis = reach::reach_registry().find("grasp.synthesis");
  const auto planner = reach::reach_registry().find("motion.reach_planner");
  ASSERT_TRUE(synthesis && planner);
  int shared = 0;
  for (const auto& p : planner->spec.params()) {
    const fba::ParamSpec* s = synthesis->spec.find_param(p.name);
    if (!s) continue;
    ++shared;
    EXPECT_EQ(s->default_value, p.default_value) << p.name;
    EXPECT_EQ(s->min, p.min) << p.name;
    EXPECT_EQ(s->max, p.max) << p.name;
    EXPECT_EQ(s->sizes, p.sizes) << p.name;
    EXPECT_EQ(s->doc, p.doc) << p.name;
  }
  // The robot's (urdf, base_pose, flange_to_palm, flange_to_camera), then base_link, flange_link, standoff, lift_height,
  // contact_allowance, max_backout, seed, ik_attempts, planning_time, path_checks.
  EXPECT_EQ(shared, 14);
  EXPECT_NE(synthesis->spec.find_input("joint_state"), nullptr);
  EXPECT_NE(synthesis->spec.find_event("unreachable"), nullptr);
}

namespace {

// motion.reach_planner with `params` on the grasp, the box's model and the arm at home(): the
// `unreachable` event's payload, or null when it planned the grasp.
nlohmann::json plan_of(const fba::Grasp& grasp, const std::vector<double>& box, const fba::testing::Params& params) {
  fba::testing::ComponentHarness h(reach::reach_registry(), "motion.reach_planner", params);
  fba::JointState joints;
  joints.names = {"shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"};
  const Eigen::VectorXd q = home();
  joints.positions.assign(q.data(), q.data() + q.size());
  h.push("octree", reach::box_model_of(box));
  h.push("joint_state", joints);
  h.push("grasp", grasp);
  h.run();
  for (const auto& e : h.events())
    if (e.name == "unreachable") return nlohmann::json::parse(e.payload);
  if (h.packets("trajectory").size() != 1) ADD_FAILURE() << "neither planned nor refused: " << h.failure();
  return nullptr;
}

}  // namespace

// The palm measured 25 cm out on the flange (the robot's parameter flange_to_palm): where the arm
// stands, the open hand's thumb is then in the table. Synthesis's reach check says so of the grasp
// it selects, in the words motion.reach_planner refuses it with, given the same parameter; with the
// URDF's palm, both find the start clear and the planner plans it.
TEST(GraspSynthesisReach, ItsReachCheckPutsThePalmWhereThePlannerDoesWhenFlangeToPalmIsSet) {
  const std::vector<double> box = reach::standing({0.06, 0.06, 0.06});
  const std::vector<double> measured{0, 0, 0.25, 0, 0, 0};
  const std::string table = "table_z: [0.001]";
  const reach::Outcome urdf_palm = reach::synthesise(box, home(), table);
  ASSERT_EQ(urdf_palm.grasps.size(), 1u) << urdf_palm.run.reason;
  EXPECT_EQ(nlohmann::json::parse(urdf_palm.result("reach"))["start"], "clear");
  EXPECT_TRUE(plan_of(urdf_palm.grasps[0], box, {}).is_null());

  const reach::Outcome measured_palm = reach::synthesise(box, home(), table + ", flange_to_palm: " + reach::numbers(measured));
  ASSERT_EQ(measured_palm.grasps.size(), 1u) << measured_palm.run.reason;
  const auto start = nlohmann::json::parse(measured_palm.result("reach"))["start"];
  ASSERT_TRUE(start.is_object()) << start;
  EXPECT_EQ(start["refusal"], "start");
  EXPECT_EQ(start["reason"].get<std::string>().rfind("the current joints collide, with the hand open for the pregrasp: ", 0), 0u) << start;
  const nlohmann::json refused = plan_of(measured_palm.grasps[0], box, {{"flange_to_palm", measured}});
  ASSERT_FALSE(refused.is_null());
  EXPECT_EQ(refused["refusal"], start["refusal"]);
  EXPECT_EQ(refused["reason"], start["reason"]);
}

// The grasp about to be selected is planned whole, path search and all, as motion.reach_planner
// plans it: with a path search that gives up at once (path_checks 1: only a straight joint-space
// line passes), the candidates whose path needs searching are passed over for "path", none is
// selected from this model, and views are asked for; with the search, the one selected is planned.
TEST(GraspSynthesisReach, TheGraspSelectedIsOneThePlannerFindsAPathFor) {
  const std::vector<double> box = reach::standing({0.06, 0.12, 0.20});  // tall: the arm's way from home to its side is searched
  const std::string table = "table_z: [0.001], edge_margin_mm: 0";
  const reach::Outcome searched = reach::synthesise(box, home(), table);
  ASSERT_EQ(searched.grasps.size(), 1u) << searched.run.reason;
  EXPECT_TRUE(plan_of(searched.grasps[0], box, {}).is_null());
  const nlohmann::json refused = plan_of(searched.grasps[0], box, {{"path_checks", std::int64_t{1}}});
  ASSERT_FALSE(refused.is_null());
  ASSERT_EQ(refused["refusal"], "path") << refused;

  const reach::Outcome straight = reach::synthesise(box, home(), table + ", path_checks: 1");
  EXPECT_TRUE(straight.grasps.empty());
  const auto report = nlohmann::json::parse(straight.result("reach"));
  ASSERT_TRUE(report["passed_over"].contains("path")) << report;
  EXPECT_EQ(report["passed_over"]["path"]["example"].get<std::string>().rfind("no collision-free path found in 1 poses checked", 0), 0u)
      << report;
  EXPECT_EQ(straight.regions.size(), 1u);
}

// A candidate the model blocks (the hand's way in runs into it: here a slab held over the box and
// walls round it, standing for space no view has carved yet) has the space the open hand sweeps
// asked for, with the regions, so that the carver refines it and carves what its views already
// show empty.
TEST(GraspSynthesisReach, TheHandsWayInForACandidateTheModelBlocksIsAskedFor) {
  // A 5 cm box 10 cm tall under a 25 cm slab 1 cm over it, walled round 3 cm from its sides from
  // 2 cm above the table up to the slab: every candidate's hand is in the slab or a wall (a pinch
  // from the side, below the slab, in a wall; lower, its palm in the table).
  std::vector<double> scene = reach::standing({0.05, 0.05, 0.10});
  for (double v : {0.0, 0.0, 0.115, 0.25, 0.25, 0.01}) scene.push_back(v);
  for (const double side : {-0.06, 0.06})
    for (double v : {side, 0.0, 0.065, 0.01, 0.13, 0.09, 0.0, side, 0.065, 0.11, 0.01, 0.09}) scene.push_back(v);
  const std::string params = "table_z: [0.001], edge_margin_mm: 0, max_views: 100";
  const reach::Outcome o = reach::synthesise(scene, home(), params);
  EXPECT_TRUE(o.grasps.empty());
  const auto report = nlohmann::json::parse(o.result("reach"));
  ASSERT_TRUE(report["passed_over"].contains("collision")) << report;
  // Without the arm the candidates' surface regions are asked for; with it, the same and the way
  // in of the three best the model blocked: each from its contacts back past the palm at the
  // standoff, reaching from the box's sides up into the slab.
  const reach::Outcome free = reach::synthesise(scene, {}, params + ", threshold: 0.99");
  ASSERT_EQ(o.regions.size(), 1u);
  ASSERT_EQ(free.regions.size(), 1u);
  int sweeps = 0;
  for (const auto& b : o.regions[0].boxes) sweeps += b.max().z() > 0.11 && b.sizes().x() > 0.15 && b.sizes().y() > 0.15;
  EXPECT_EQ(sweeps, 3);
  for (const auto& b : free.regions[0].boxes) EXPECT_FALSE(b.sizes().x() > 0.15 && b.sizes().y() > 0.15);
}

// After each analysis synthesis shows its first candidates for a live view, the best one with its
// palm at the pregrasp: on the model a grasp is selected from, the selected grasp, its palm where
// the reach planner puts it.
TEST(GraspSynthesisReach, TheCandidatesShownHoldTheSelectedGraspWithItsPalmWhereThePlannerPutsIt) {
  const std::vector<double> box = reach::standing({0.06, 0.06, 0.06});
  const reach::Outcome out = reach::synthesise(box, home(), "table_z: [0.001]");
  ASSERT_EQ(out.grasps.size(), 1u) << out.run.reason;
  ASSERT_FALSE(out.candidates.empty());
  const fba::GraspCandidates& last = out.candidates.back();
  EXPECT_EQ(last.total, nlohmann::json::parse(out.result("candidates"))["grasps"].size());
  std::vector<const fba::GraspCandidates::Candidate*> with_palm;
  for (const auto& c : last.candidates)
    if (c.palm) with_palm.push_back(&c);
  ASSERT_EQ(with_palm.size(), 1u) << "the best one's palm only";
  EXPECT_TRUE(same_contacts(with_palm[0]->grasp, out.grasps[0])) << "the best is the one selected";
  const fba::motion::ReachPlan plan = reach_planner().plan(out.grasps[0], reach::box_model_of(box), home());
  ASSERT_TRUE(plan.ok) << plan.why;
  EXPECT_TRUE(with_palm[0]->palm->isApprox(plan.pregrasp_palm, 1e-9)) << with_palm[0]->palm->matrix() << "\n" << plan.pregrasp_palm.matrix();
}
