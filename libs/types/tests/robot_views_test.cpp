// The views of the robot types (libs/types/src/robot_views.cpp) against docs/live-view.md.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include <fba/types/grasp.hpp>
#include <fba/types/joint_state.hpp>
#include <fba/types/joint_trajectory.hpp>
#include <fba/types/pose.hpp>
#include <fba/types/regions_of_interest.hpp>
#include <fba/types/robot_description.hpp>

#include "view_checks.hpp"

using fba::test::json;
using fba::test::numbers;
using fba::test::view_of;

namespace {

Eigen::Vector3d vec(const json& j) { return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()}; }

}  // namespace

TEST(PoseView, RoundTripsThePoseWithinItsRounding) {
  for (const Eigen::Vector4d& axis_angle : {Eigen::Vector4d(0, 0, 1, 0), Eigen::Vector4d(1, 2, 3, 2.5),
                                            Eigen::Vector4d(-1, 0.2, 0, 3.14159), Eigen::Vector4d(0, 1, 0, -1)}) {
    fba::Pose pose;
    pose.world_from_frame = Eigen::Translation3d(0.4125, -0.13, 0.91) *
                            Eigen::AngleAxisd(axis_angle[3], axis_angle.head<3>().normalized());
    pose.stamp = 2.5;
    const json v = view_of(pose);
    ASSERT_EQ(v["kind"], "pose");
    ASSERT_TRUE(numbers(v["position"], 3));
    ASSERT_TRUE(numbers(v["rotation"], 4));
    const Eigen::Quaterniond q(v["rotation"][0].get<double>(), v["rotation"][1].get<double>(), v["rotation"][2].get<double>(),
                               v["rotation"][3].get<double>());
    EXPECT_NEAR(q.norm(), 1, 1e-5);
    const Eigen::Isometry3d back = Eigen::Translation3d(vec(v["position"])) * q.normalized();
    EXPECT_LT((back.translation() - pose.world_from_frame.translation()).norm(), 1e-5);
    EXPECT_LT(Eigen::AngleAxisd(back.linear().transpose() * pose.world_from_frame.linear()).angle(), 1e-5);
    EXPECT_GE(q.w(), 0) << "one of the two quaternions of a rotation, always the same";
    EXPECT_EQ(v["stamp"], 2.5);
  }
}

TEST(JointStateView, HoldsNamesAndPositionsInOrderAndNoNumberJsonCannotHold) {
  fba::JointState s;
  s.names = {"shoulder_pan", "elbow", "wrist_\xff"};  // invalid UTF-8 from a device: replaced, not thrown on
  s.positions = {0.5, -1.25, std::numeric_limits<double>::quiet_NaN()};
  const json v = view_of(s);
  ASSERT_EQ(v["kind"], "joints");
  ASSERT_EQ(v["names"].size(), 3u);
  EXPECT_EQ(v["names"][0], "shoulder_pan");
  ASSERT_EQ(v["positions"].size(), 3u);
  EXPECT_EQ(v["positions"][1], -1.25);
  EXPECT_TRUE(v["positions"][2].is_null());
  EXPECT_FALSE(v.contains("velocities")) << "a target has none";
}

TEST(TrajectoryView, KeepsTheFirstAndLastWaypointsWhenItHasToThin) {
  fba::JointTrajectory t;
  t.names = {"a", "b"};
  constexpr std::size_t n = 2500;
  for (std::size_t i = 0; i < n; ++i) t.points.push_back({0.01 * static_cast<double>(i), {double(i), -double(i)}, {}});
  const json v = view_of(t);
  ASSERT_EQ(v["kind"], "trajectory");
  EXPECT_EQ(v["names"], json::array({"a", "b"}));
  ASSERT_EQ(v["points"].size(), 1000u);
  EXPECT_EQ(v["points"].front()["t"], 0);
  EXPECT_EQ(v["points"].back()["positions"][0], double(n - 1));
  EXPECT_EQ(v["truncated"], true);
  EXPECT_EQ(v["point_count"], n);
  double previous = -1;
  for (const json& p : v["points"]) {
    ASSERT_TRUE(numbers(p["positions"], 2));
    EXPECT_GT(p["t"].get<double>(), previous);
    previous = p["t"].get<double>();
  }

  t.points.resize(3);
  const json small = view_of(t);
  EXPECT_EQ(small["points"].size(), 3u);
  EXPECT_FALSE(small.contains("truncated"));
}

TEST(GraspView, IsTheSelectedGraspWithItsContactsNormalsAndApproach) {
  fba::Grasp g;
  for (int i = 0; i < 3; ++i) {
    g.contacts[static_cast<std::size_t>(i)].position = Eigen::Vector3d(0.01 * i, 0.02, 0.15);
    g.contacts[static_cast<std::size_t>(i)].normal = Eigen::Vector3d(i == 0 ? 1 : -1, 0, 0);
  }
  g.approach = Eigen::Vector3d(0, 0, -1);
  g.scores.total = 0.8125;
  g.views = {0, 3, 4};
  const json v = view_of(g);
  ASSERT_EQ(v["kind"], "grasps");
  EXPECT_EQ(v["candidates"], json::array()) << "the type carries the selected grasp only";
  const json& s = v["selected"];
  ASSERT_EQ(s["contacts"].size(), 3u);
  ASSERT_EQ(s["normals"].size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    ASSERT_TRUE(numbers(s["contacts"][i], 3));
    EXPECT_LT((vec(s["contacts"][i]) - g.contacts[i].position).norm(), 1e-9);
    EXPECT_LT((vec(s["normals"][i]) - g.contacts[i].normal).norm(), 1e-9);
  }
  EXPECT_LT((vec(s["approach"]) - g.approach).norm(), 1e-9);
  EXPECT_EQ(s["score"], 0.8125);
  EXPECT_TRUE(s["palm"].is_null());
  EXPECT_EQ(s["views"], json::array({0, 3, 4}));
}

TEST(GraspCandidatesView, HoldsEachCandidateInOrderAndTheBestOnesPalm) {
  fba::GraspCandidates gc;
  for (int k = 0; k < 3; ++k) {
    fba::GraspCandidates::Candidate c;
    for (int i = 0; i < 3; ++i) c.grasp.contacts[static_cast<std::size_t>(i)].position = Eigen::Vector3d(0.01 * i, 0.02 * k, 0.15);
    c.grasp.approach = Eigen::Vector3d(0, 0, -1);
    c.grasp.scores.total = 0.5 - 0.125 * k;
    c.reliable = k == 1;
    c.passed_over = k == 0;
    gc.candidates.push_back(c);
  }
  const Eigen::Isometry3d palm = Eigen::Translation3d(0.05, -0.02, 0.3) * Eigen::AngleAxisd(2.5, Eigen::Vector3d(1, 0, 0));
  gc.candidates[1].palm = palm;
  gc.total = 40;
  gc.views = 4;
  const json v = view_of(gc);
  ASSERT_EQ(v["kind"], "grasps");
  EXPECT_TRUE(v["selected"].is_null()) << "candidates, none selected";
  EXPECT_EQ(v["total"], 40);
  EXPECT_EQ(v["views"], 4);
  ASSERT_EQ(v["candidates"].size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    const json& c = v["candidates"][k];
    EXPECT_EQ(c["score"], gc.candidates[k].grasp.scores.total);
    EXPECT_LT((vec(c["contacts"][2]) - gc.candidates[k].grasp.contacts[2].position).norm(), 1e-9);
    EXPECT_EQ(c["reliable"], gc.candidates[k].reliable);
    EXPECT_EQ(c["passed_over"], gc.candidates[k].passed_over);
    EXPECT_EQ(c["palm"].is_null(), k != 1);
  }
  const json& p = v["candidates"][1]["palm"];
  ASSERT_TRUE(numbers(p["position"], 3) && numbers(p["rotation"], 4)) << p;
  EXPECT_LT((vec(p["position"]) - palm.translation()).norm(), 1e-5);
  const Eigen::Quaterniond q(p["rotation"][0].get<double>(), p["rotation"][1].get<double>(), p["rotation"][2].get<double>(),
                             p["rotation"][3].get<double>());
  EXPECT_LT(Eigen::AngleAxisd(q.normalized().toRotationMatrix().transpose() * palm.linear()).angle(), 1e-5);
}

TEST(RobotView, HoldsTheUrdfAsGivenAndItsName) {
  fba::RobotDescription r;
  r.urdf = "<robot name=\"arm\"><link name=\"base_link\"/></robot>\n";
  r.name = "arm.urdf (with the parameters base_pose)";
  const json v = view_of(r);
  ASSERT_EQ(v["kind"], "robot");
  EXPECT_EQ(v["urdf"], r.urdf);
  EXPECT_EQ(v["name"], r.name);
}

TEST(RegionsView, HoldsEachBoxAsMinThenMaxAndSkipsEmptyOnes) {
  fba::RegionsOfInterest r;
  r.boxes.emplace_back(Eigen::Vector3d(-0.1, 0, 0.2), Eigen::Vector3d(0.05, 0.125, 0.3));
  r.boxes.emplace_back();  // empty
  r.points.push_back({Eigen::Vector3d(0.01, 0.02, 0.03), Eigen::Vector3d(0, 0, 1), 2});
  const json v = view_of(r);
  ASSERT_EQ(v["kind"], "regions");
  ASSERT_EQ(v["boxes"].size(), 1u);
  EXPECT_EQ(v["boxes"][0], json::array({-0.1, 0, 0.2, 0.05, 0.125, 0.3}));
  ASSERT_EQ(v["points"].size(), 1u);
  EXPECT_EQ(v["points"][0]["group"], 2);
}
