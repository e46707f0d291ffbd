// Next-best-view choice on hand-built octrees whose answers are known: which side of a box sees a
// region, an occluder hiding it, and the movement cost deciding between equal gains.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>

#include "fba/geometry/viewpoints.hpp"
#include "fba/grasp/exploration.hpp"

using fba::NodeState;
using fba::Octree;
using fba::grasp::choose_view;
using fba::grasp::ExplorationParams;

namespace {

// The cube [-1, 1]^3 split uniformly to depth 3 (8 x 8 x 8 leaves of edge 0.25), each leaf's state
// given by its lattice index.
Octree uniform_model(const std::function<NodeState(int, int, int)>& state) {
  Octree m;
  m.bounds = Eigen::AlignedBox3d(Eigen::Vector3d::Constant(-1), Eigen::Vector3d::Constant(1));
  m.max_depth = 3;
  std::function<void(fba::OctreeNode&, int, int, int, int)> build = [&](fba::OctreeNode& n, int depth, int x, int y,
                                                                         int z) {
    if (depth == 3) {
      n.set_state(state(x, y, z));
      return;
    }
    fba::OctreeNode* k = m.split(n, NodeState::Partial);
    for (int i = 0; i < 8; ++i) build(k[i], depth + 1, 2 * x + (i & 1), 2 * y + ((i >> 1) & 1), 2 * z + ((i >> 2) & 1));
  };
  build(m.root, 0, 0, 0, 0);
  return m;
}

// A solid box: leaves 2..5 on every axis (the cube [-0.5, 0.5]^3), its outer layer Partial (the
// silhouettes' uncertain boundary), the inside Full.
NodeState box_state(int x, int y, int z) {
  auto in = [](int i) { return i >= 2 && i <= 5; };
  auto edge = [](int i) { return i == 2 || i == 5; };
  if (!in(x) || !in(y) || !in(z)) return NodeState::Empty;
  return edge(x) || edge(y) || edge(z) ? NodeState::Partial : NodeState::Full;
}

// The +x face of the box: its Partial leaves at x index 5.
fba::RegionsOfInterest plus_x_face() {
  return {{Eigen::AlignedBox3d(Eigen::Vector3d(0.3, -0.3, -0.3), Eigen::Vector3d(0.45, 0.3, 0.3))}};
}

// A camera at `eye` looking at the origin, as world_from_camera.
Eigen::Isometry3d camera_at(const Eigen::Vector3d& eye) { return fba::geometry::look_at(eye, Eigen::Vector3d::Zero()).inverse(); }

}  // namespace

TEST(Exploration, UncertainTargetsArePartialLeavesInsideTheRegions) {
  const Octree m = uniform_model(box_state);
  const auto targets = fba::grasp::uncertain_targets(m, plus_x_face());
  // The region meets x index 5 and y, z indices 2..5: 16 leaves, all Partial (on the box's face).
  ASSERT_EQ(targets.size(), 16u);
  for (const auto& t : targets) {
    EXPECT_EQ(t.x, 5);
    EXPECT_EQ(t.state(), NodeState::Partial);
  }
  EXPECT_TRUE(fba::grasp::uncertain_targets(m, {}).empty());
}

TEST(Exploration, ARegionOnOneSideIsSeenFromThatSideAndNotFromBehind) {
  const Octree m = uniform_model(box_state);
  const std::vector<Eigen::Isometry3d> views{camera_at({-4, 0, 0}), camera_at({4, 0, 0}), camera_at({0, 4, 0})};
  const auto choice = choose_view(m, plus_x_face(), views);
  ASSERT_TRUE(choice.best.has_value()) << choice.reason;
  EXPECT_EQ(*choice.best, 1u) << choice.reason;
  EXPECT_EQ(choice.targets, 16u);
  EXPECT_EQ(choice.scores[1].seen, 16u);  // the whole face, from in front of it
  EXPECT_EQ(choice.scores[0].seen, 0u);   // from behind, the box's inside hides every node
  EXPECT_EQ(choice.scores[0].hidden, 16u);
  // From the side only the nearest row of the face is not behind the rest of the surface.
  EXPECT_GT(choice.scores[2].seen, 0u);
  EXPECT_LT(choice.scores[2].seen, 16u);
  EXPECT_NE(choice.reason.find("view 1 sees 16 of the 16"), std::string::npos) << choice.reason;
}

TEST(Exploration, AnOccluderHidesTheRegion) {
  // A wall at x index 7 (x in [0.75, 1]) in front of the +x face.
  const Octree walled = uniform_model([](int x, int y, int z) {
    if (x == 7 && y >= 1 && y <= 6 && z >= 1 && z <= 6) return NodeState::Full;
    return box_state(x, y, z);
  });
  const std::vector<Eigen::Isometry3d> views{camera_at({4, 0, 0}), camera_at({-4, 0, 0})};
  const auto choice = choose_view(walled, plus_x_face(), views);
  EXPECT_EQ(choice.scores[0].seen, 0u);
  EXPECT_EQ(choice.scores[0].hidden, 16u);
  EXPECT_FALSE(choice.best.has_value());
  EXPECT_NE(choice.reason.find("no unvisited view is worth the move"), std::string::npos) << choice.reason;
  // Without the wall the same view sees the whole face.
  EXPECT_EQ(choose_view(uniform_model(box_state), plus_x_face(), views).scores[0].seen, 16u);
}

TEST(Exploration, WithEqualGainTheNearerViewWins) {
  // A region around the whole box: views from +x and -x see mirror images of it.
  const fba::RegionsOfInterest all{{Eigen::AlignedBox3d(Eigen::Vector3d::Constant(-1), Eigen::Vector3d::Constant(1))}};
  const Octree m = uniform_model(box_state);
  const std::vector<Eigen::Isometry3d> views{camera_at({4, 0, 0}), camera_at({-4, 0, 0})};
  const double a = 20 * std::numbers::pi / 180;
  const auto near_plus = choose_view(m, all, views, camera_at({4 * std::cos(a), 4 * std::sin(a), 0}));
  ASSERT_EQ(near_plus.scores[0].seen, near_plus.scores[1].seen);
  ASSERT_TRUE(near_plus.best.has_value());
  EXPECT_EQ(*near_plus.best, 0u) << near_plus.reason;
  EXPECT_NEAR(near_plus.scores[0].move_angle, a, 1e-9);
  const auto near_minus = choose_view(m, all, views, camera_at({-4 * std::cos(a), 4 * std::sin(a), 0}));
  ASSERT_TRUE(near_minus.best.has_value());
  EXPECT_EQ(*near_minus.best, 1u) << near_minus.reason;
}

TEST(Exploration, ExcludedViewsAreNeverChosen) {
  const Octree m = uniform_model(box_state);
  const std::vector<Eigen::Isometry3d> views{camera_at({4, 0, 0}), camera_at({0, 4, 0})};
  const auto choice = choose_view(m, plus_x_face(), views, std::nullopt, {true, false});
  ASSERT_TRUE(choice.best.has_value());
  EXPECT_EQ(*choice.best, 1u);
  const auto none = choose_view(m, plus_x_face(), views, std::nullopt, {true, true});
  EXPECT_FALSE(none.best.has_value());
  EXPECT_NE(none.reason.find("none of the 2 candidate views is left to take (each visited or excluded)"), std::string::npos) << none.reason;
}

TEST(Exploration, NothingUncertainLeftGivesNoViewWithTheReason) {
  const Octree m = uniform_model([](int x, int y, int z) {
    const NodeState s = box_state(x, y, z);
    return s == NodeState::Partial ? NodeState::Full : s;
  });
  const std::vector<Eigen::Isometry3d> views{camera_at({4, 0, 0})};
  const auto choice = choose_view(m, plus_x_face(), views);
  EXPECT_FALSE(choice.best.has_value());
  EXPECT_EQ(choice.targets, 0u);
  EXPECT_NE(choice.reason.find("no uncertain node"), std::string::npos) << choice.reason;
}

TEST(Exploration, RaysAreCappedWithAnEvenStride) {
  const Octree m = uniform_model(box_state);
  ExplorationParams p;
  p.max_rays = 4;
  const std::vector<Eigen::Isometry3d> views{camera_at({4, 0, 0})};
  const auto choice = choose_view(m, plus_x_face(), views, std::nullopt, {}, p);
  EXPECT_EQ(choice.targets, 16u);
  EXPECT_EQ(choice.rays, 4u);
  EXPECT_EQ(choice.scores[0].seen, 4u);
}

TEST(Exploration, BadParametersAreRefusedNamingTheValues) {
  const Octree m = uniform_model(box_state);
  const std::vector<Eigen::Isometry3d> views{camera_at({4, 0, 0})};
  ExplorationParams p;
  p.movement_weight = -1;
  try {
    choose_view(m, plus_x_face(), views, std::nullopt, {}, p);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("movement_weight >= 0"), std::string::npos) << e.what();
  }
  EXPECT_THROW(choose_view(m, plus_x_face(), views, std::nullopt, {true, false}), std::invalid_argument);
}

namespace {

// The +x face's region, asking also for its centre (0.5, 0, 0), normal +x, to be pinned down.
fba::RegionsOfInterest plus_x_contact() {
  fba::RegionsOfInterest r = plus_x_face();
  r.points.push_back({Eigen::Vector3d(0.5, 0, 0), Eigen::Vector3d::UnitX()});
  r.rim_deg = 15;
  r.rim_separation_deg = 20;
  return r;
}

}  // namespace

TEST(ExplorationGrazing, AContactIsPinnedByTheViewThatGrazesItInANewDirectionNotByTheOneFacingIt) {
  const Octree m = uniform_model(box_state);
  // Facing the contact (sees every uncertain node of the face), grazing it from +y at the height of
  // the contact (the view taken already), grazing it from above +y at 45 deg, and behind the box.
  const std::vector<Eigen::Isometry3d> views{camera_at({4, 0, 0}), camera_at({0, 4, 0}),
                                             camera_at({0, 4 / std::sqrt(2.0), 4 / std::sqrt(2.0)}), camera_at({-4, 0, 0})};
  const std::vector<Eigen::Vector3d> taken{{0, 4, 0}};
  const auto choice = choose_view(m, plus_x_contact(), views, std::nullopt, {false, true, false, false}, {}, taken);
  ASSERT_TRUE(choice.best.has_value()) << choice.reason;
  EXPECT_TRUE(choice.by_points);
  EXPECT_EQ(choice.points, 1u);
  EXPECT_EQ(*choice.best, 2u) << choice.reason;
  EXPECT_EQ(choice.scores[2].pins, 1u);                                   // 45 deg from the taken line of sight
  EXPECT_EQ(choice.scores[0].pins + choice.scores[0].first, 0u);         // facing it: not on its rim
  EXPECT_EQ(choice.scores[3].pins + choice.scores[3].first, 0u);         // behind the box
  // The node count alone chooses the facing view, which sees the whole face.
  const auto by_nodes = choose_view(m, plus_x_face(), views, std::nullopt, {false, true, false, false}, {}, taken);
  ASSERT_TRUE(by_nodes.best.has_value()) << by_nodes.reason;
  EXPECT_EQ(*by_nodes.best, 0u) << by_nodes.reason;
  EXPECT_EQ(by_nodes.scores[0].seen, 16u);
  EXPECT_NE(choice.reason.find("view 2 grazes 1 of the 1 surface points"), std::string::npos) << choice.reason;
}

TEST(ExplorationGrazing, TheOppositeSideRepeatsTheTakenLineOfSightAndDoesNotCount) {
  const Octree m = uniform_model(box_state);
  // From -y the line of sight to the contact is the one from +y reversed: the same tangent line.
  const std::vector<Eigen::Isometry3d> views{camera_at({4, 0, 0}), camera_at({0, -4, 0})};
  const std::vector<Eigen::Vector3d> taken{{0, 4, 0}};
  const auto choice = choose_view(m, plus_x_contact(), views, std::nullopt, {}, {}, taken);
  EXPECT_EQ(choice.scores[1].pins + choice.scores[1].first, 0u);
  // No view grazes usefully: the choice falls back to the uncertain nodes, the facing view.
  EXPECT_FALSE(choice.by_points);
  ASSERT_TRUE(choice.best.has_value()) << choice.reason;
  EXPECT_EQ(*choice.best, 0u) << choice.reason;
}

TEST(ExplorationGrazing, WithNoGrazingViewTakenAFirstOneCountsHalf) {
  const Octree m = uniform_model(box_state);
  const std::vector<Eigen::Isometry3d> views{camera_at({4, 0, 0}), camera_at({0, 4, 0})};
  const auto choice = choose_view(m, plus_x_contact(), views);
  ASSERT_TRUE(choice.best.has_value()) << choice.reason;
  EXPECT_EQ(*choice.best, 1u) << choice.reason;
  EXPECT_EQ(choice.scores[1].first, 1u);
  EXPECT_DOUBLE_EQ(choice.scores[1].gain, 0.5);
}

TEST(ExplorationGrazing, AContactAlreadyPinnedAsksForNothing) {
  const Octree m = uniform_model(box_state);
  const std::vector<Eigen::Isometry3d> views{camera_at({4, 0, 0})};
  const std::vector<Eigen::Vector3d> taken{{0, 4, 0}, {0, 4 / std::sqrt(2.0), 4 / std::sqrt(2.0)}};
  const auto choice = choose_view(m, plus_x_contact(), views, std::nullopt, {}, {}, taken);
  EXPECT_EQ(choice.points, 0u);
  EXPECT_FALSE(choice.by_points);
}

TEST(ExplorationGrazing, AGrazingLineOfSightBehindAnOccluderDoesNotCount) {
  // A pillar beside the +x face, between the contact and the camera at +y.
  const Octree pillar = uniform_model([](int x, int y, int z) {
    if (x == 6 && y == 7 && (z == 3 || z == 4)) return NodeState::Full;
    return box_state(x, y, z);
  });
  const std::vector<Eigen::Isometry3d> views{camera_at({0, 4, 0})};
  EXPECT_EQ(choose_view(pillar, plus_x_contact(), views).scores[0].first, 0u);
  EXPECT_EQ(choose_view(uniform_model(box_state), plus_x_contact(), views).scores[0].first, 1u);
}

TEST(ExplorationGrazing, AGrazingLineOfSightWithTheObjectBehindThePointDoesNotCount) {
  // A block standing out past the +x face, beyond the contact from the camera at +y: the line of
  // sight past the contact runs into it, so the contact projects inside the silhouette, not on its
  // rim (a handle seen against the tool's head).
  const Octree with_block = uniform_model([](int x, int y, int z) {
    if (x >= 6 && y <= 1 && (z == 3 || z == 4)) return NodeState::Full;
    return box_state(x, y, z);
  });
  const std::vector<Eigen::Isometry3d> views{camera_at({0, 4, 0})};
  EXPECT_TRUE(fba::grasp::backed(with_block, {0, 4, 0}, {0.5, 0, 0}, Eigen::Vector3d::UnitX()));
  EXPECT_EQ(choose_view(with_block, plus_x_contact(), views).scores[0].first, 0u);
  // From -y the block stands in front of the contact (occluded), not behind it.
  EXPECT_FALSE(fba::grasp::backed(with_block, {0, -4, 0}, {0.5, 0, 0}, Eigen::Vector3d::UnitX()));
  EXPECT_TRUE(fba::grasp::occluded(with_block, {0, -4, 0}, {0.5, 0, 0}, Eigen::Vector3d::UnitX()));
  EXPECT_FALSE(fba::grasp::backed(uniform_model(box_state), {0, 4, 0}, {0.5, 0, 0}, Eigen::Vector3d::UnitX()));
  // A view taken from +y gave the contact no rim: a view from above +y is its first, not its pair.
  const std::vector<Eigen::Vector3d> taken{{0, 4, 0}};
  const std::vector<Eigen::Isometry3d> above{camera_at({0, 4 / std::sqrt(2.0), 4 / std::sqrt(2.0)})};
  const auto choice = choose_view(with_block, plus_x_contact(), above, std::nullopt, {}, {}, taken);
  EXPECT_EQ(choice.scores[0].pins, 0u);
  EXPECT_EQ(choice.scores[0].first, 1u);
  EXPECT_EQ(choose_view(uniform_model(box_state), plus_x_contact(), above, std::nullopt, {}, {}, taken).scores[0].pins, 1u);
}

TEST(ExplorationGrazing, AFacesOwnVoxelStaircaseDoesNotHideItsPointFromALineOfSightAlongIt) {
  // A face tilted 27 deg from the lattice, through the origin: voxels whose centre lies below 0.1
  // along its normal are full, so the face is a staircase whose steps stand up to 0.22 above the
  // plane. A line of sight 8 deg off the plane, from behind it (within any rim tolerance), climbs
  // through the steps to the probe one leaf edge out: the steps are the face the view grazes.
  const Eigen::Vector3d n = Eigen::Vector3d(2, 1, 0).normalized(), along = Eigen::Vector3d(-1, 2, 0).normalized();
  const double lean = 8 * std::numbers::pi / 180;
  const Eigen::Vector3d eye = 4 * (along * std::cos(lean) - n * std::sin(lean));
  auto centre = [](int i) { return -1 + 0.25 * (i + 0.5); };
  const Octree face = uniform_model([&](int x, int y, int z) {
    return Eigen::Vector3d(centre(x), centre(y), centre(z)).dot(n) < 0.1 ? NodeState::Full : NodeState::Empty;
  });
  EXPECT_FALSE(fba::grasp::occluded(face, eye, Eigen::Vector3d::Zero(), n));
  // The same line of sight to a point a step lower: the body in front of it now hides it.
  EXPECT_TRUE(fba::grasp::occluded(face, eye, -0.6 * n, n));
}

TEST(ExplorationGrazing, ABadSurfacePointIsRefusedNamingIt) {
  const Octree m = uniform_model(box_state);
  const std::vector<Eigen::Isometry3d> views{camera_at({4, 0, 0})};
  auto r = plus_x_contact();
  r.points[0].normal = Eigen::Vector3d::Zero();
  try {
    choose_view(m, r, views);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("non-zero normal"), std::string::npos) << e.what();
  }
  r = plus_x_contact();
  r.rim_deg = 0;
  EXPECT_THROW(choose_view(m, r, views), std::invalid_argument);
}

TEST(Exploration, AViewThatSeesTheRegionIsChosenHoweverFarWhenTheNearOnesSeeNothing) {
  // The camera is behind the box; moving to the front costs more than the whole gain, but staying
  // behind sees nothing: the cost ranks the views worth the move, it does not end the exploration.
  const Octree m = uniform_model(box_state);
  const std::vector<Eigen::Isometry3d> views{camera_at({-4, 0, 0.1}), camera_at({4, 0, 0})};
  ExplorationParams p;
  p.movement_weight = 2;
  const auto choice = choose_view(m, plus_x_face(), views, camera_at({-4, 0, 0}), {}, p);
  ASSERT_GT(choice.scores[0].score, choice.scores[1].score);
  ASSERT_TRUE(choice.best.has_value()) << choice.reason;
  EXPECT_EQ(*choice.best, 1u) << choice.reason;
}
