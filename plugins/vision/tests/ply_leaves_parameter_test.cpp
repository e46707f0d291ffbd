// The ply_leaves parameter that vision.octree_carver and grasp.synthesis share: each of its
// choices names its own leaves, and its default the seen ones.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "fba/vision/ply_leaves_parameter.hpp"

using fba::vision::PlyLeaves;
using fba::vision::PlyLeavesParameter;

TEST(PlyLeavesParameter, EachChoiceNamesItsOwnLeaves) {
  const fba::ParamSpec spec = PlyLeavesParameter::kPlyLeaves.spec();
  EXPECT_EQ(spec.name, "ply_leaves");
  ASSERT_EQ(spec.choices.size(), 2u);
  std::set<PlyLeaves> named;
  for (const std::string& choice : spec.choices) named.insert(PlyLeavesParameter::named(choice));
  EXPECT_EQ(named.size(), spec.choices.size());
  EXPECT_EQ(PlyLeavesParameter::named("seen"), PlyLeaves::Seen);
  EXPECT_EQ(PlyLeavesParameter::named("occupied"), PlyLeaves::Occupied);
}

TEST(PlyLeavesParameter, TheDefaultIsTheSeenLeaves) {
  const fba::ParamSpec spec = PlyLeavesParameter::kPlyLeaves.spec();
  ASSERT_TRUE(spec.default_value.has_value());
  EXPECT_EQ(PlyLeavesParameter::named(std::get<std::string>(*spec.default_value)), PlyLeaves::Seen);
}
