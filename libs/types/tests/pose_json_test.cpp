// A pose as JSON (fba/types/pose_json.hpp): the shape events and summary.json give web/.
#include <gtest/gtest.h>

#include <cmath>

#include <fba/types/pose_json.hpp>

TEST(PoseJson, IsThePositionAndTheRotationAsAQuaternionWFirst) {
  const Eigen::Isometry3d t = Eigen::Translation3d(0.25, -0.5, 1.0) * Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ());
  const nlohmann::json j = fba::pose_json(t);
  EXPECT_EQ(j["position"], nlohmann::json::array({0.25, -0.5, 1.0}));
  ASSERT_EQ(j["quaternion_wxyz"].size(), 4u);
  EXPECT_NEAR(j["quaternion_wxyz"][0].get<double>(), std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(j["quaternion_wxyz"][1].get<double>(), 0, 1e-12);
  EXPECT_NEAR(j["quaternion_wxyz"][2].get<double>(), 0, 1e-12);
  EXPECT_NEAR(j["quaternion_wxyz"][3].get<double>(), std::sqrt(0.5), 1e-12);
}
