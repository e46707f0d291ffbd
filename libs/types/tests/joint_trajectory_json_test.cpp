// A trajectory's JSON (fba/types/joint_trajectory_json.hpp): whole and exact for summary.json,
// thinned and rounded for the live view, in the same shape.
#include <gtest/gtest.h>

#include <fba/types/joint_trajectory_json.hpp>

TEST(TrajectoryJson, KeepsEveryWaypointAndEveryDigitUnlessAskedNotTo) {
  fba::JointTrajectory t;
  t.names = {"a", "b"};
  for (int i = 0; i < 5; ++i) t.points.push_back({0.1 * i + 1e-9, {1.0 / 3 + i, -2.0 / 3}, {0.5, 0.5}});
  const nlohmann::json whole = fba::trajectory_json(t);
  EXPECT_EQ(whole["names"], nlohmann::json::array({"a", "b"}));
  ASSERT_EQ(whole["points"].size(), 5u);
  for (std::size_t i = 0; i < 5; ++i) {
    EXPECT_EQ(whole["points"][i]["t"].get<double>(), t.points[i].time);
    EXPECT_EQ(whole["points"][i]["positions"].get<std::vector<double>>(), t.points[i].positions);
  }
  EXPECT_FALSE(whole.contains("truncated"));
  EXPECT_FALSE(whole["points"][0].contains("velocities")) << "they follow from the positions";

  const nlohmann::json thin = fba::trajectory_json(t, 3, 1e6);
  ASSERT_EQ(thin["points"].size(), 3u);
  EXPECT_EQ(thin["points"][0]["t"].get<double>(), 0.0) << "rounded to a millionth";
  EXPECT_EQ(thin["points"][1]["positions"][0].get<double>(), 2.333333) << "the middle waypoint, rounded";
  EXPECT_EQ(thin["points"][2]["t"].get<double>(), 0.4) << "the last waypoint kept";
  EXPECT_EQ(thin["truncated"], true);
  EXPECT_EQ(thin["point_count"], 5u);
}
