// A grasp's execution as JSON (fba/types/grasp_execution_json.hpp): the hands' events' payload.
#include <gtest/gtest.h>

#include <fba/types/grasp_execution_json.hpp>

TEST(GraspExecutionJson, HoldsWhatEveryHandReportsAndEachContact) {
  fba::GraspExecution e;
  e.held = false;
  e.hold_s = 0.75;
  e.reason = "dropped: finger B lost its contact";
  e.slip_m = 0.01;  // measured by a simulation only: not written here
  e.contacts.push_back({"finger_a", Eigen::Vector3d(0.03, 0, 0.05), Eigen::Vector3d(-1, 0, 0), 12.5});
  const nlohmann::json j = fba::grasp_execution_json(e);
  EXPECT_EQ(j["held"], false);
  EXPECT_EQ(j["hold_s"], 0.75);
  EXPECT_EQ(j["reason"], e.reason);
  EXPECT_FALSE(j.contains("slip_m"));
  ASSERT_EQ(j["contacts"].size(), 1u);
  EXPECT_EQ(j["contacts"][0]["link"], "finger_a");
  EXPECT_EQ(j["contacts"][0]["position"], nlohmann::json::array({0.03, 0, 0.05}));
  EXPECT_EQ(j["contacts"][0]["normal"], nlohmann::json::array({-1, 0, 0}));
  EXPECT_EQ(j["contacts"][0]["force"], 12.5);
}
