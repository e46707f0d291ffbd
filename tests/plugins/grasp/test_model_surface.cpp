// Surface samples of octree models of known shapes: outward normals, the curvature's sign and
// size, and the uncertainty of parts not yet refined.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "fba/grasp/model_surface.hpp"
#include "fba/grasp/object_surface.hpp"
#include "voxel_shapes.hpp"

namespace fba::grasp {
namespace {

constexpr double kPi = std::numbers::pi;
const Eigen::AlignedBox3d kCube(Eigen::Vector3d::Constant(-0.08), Eigen::Vector3d::Constant(0.08));

double angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180 / kPi;
}

TEST(ModelSurface, SphereNormalsPointOutwardAndCurvatureIsNearOneOverR) {
  const double r = 0.05;
  const Octree model = test::voxelise(test::sphere_sdf(Eigen::Vector3d::Zero(), r), kCube, 6);  // 2.5 mm leaves
  const ModelSurface s = model_surface(model);
  ASSERT_GT(s.samples.size(), 1000u);
  EXPECT_DOUBLE_EQ(s.finest_edge, 0.16 / 64);
  std::vector<double> angles, curvature;
  for (const auto& x : s.samples) {
    EXPECT_NEAR(x.position.norm(), r, 2 * s.finest_edge);
    angles.push_back(angle_deg(x.normal, x.position));
    curvature.push_back(x.curvature);
    EXPECT_FALSE(x.uncertain);
  }
  EXPECT_LT(quantile(angles, 0.5), 5.0);
  EXPECT_LT(quantile(angles, 0.99), 15.0);
  // Mean curvature of a sphere is 1/r = 20 /m: positive (convex) everywhere it is measured.
  EXPECT_NEAR(quantile(curvature, 0.5), 1 / r, 0.3 / r);
  EXPECT_GT(quantile(curvature, 0.05), 0.0);
}

TEST(ModelSurface, BoxFaceNormalsAreTheFaceAxisAndFacesAreFlat) {
  const Eigen::Vector3d size(0.06, 0.08, 0.10);
  const Octree model = test::voxelise(test::box_sdf(Eigen::Vector3d(0.003, -0.002, 0.001), size), kCube, 6);
  const ModelSurface s = model_surface(model);
  ASSERT_GT(s.samples.size(), 500u);
  std::vector<double> curvature;
  int on_faces = 0;
  for (const auto& x : s.samples) {
    // Away from the edges by more than the neighbourhood: on one face.
    const Eigen::Vector3d q = (x.position - Eigen::Vector3d(0.003, -0.002, 0.001)).cwiseAbs() - size / 2;
    int axis;
    q.maxCoeff(&axis);
    Eigen::Vector3d rest = q;
    rest[axis] = -1;
    if (rest.maxCoeff() > -s.radius - s.finest_edge) continue;
    ++on_faces;
    Eigen::Vector3d want = Eigen::Vector3d::Zero();
    want[axis] = x.position[axis] > 0 ? 1 : -1;
    EXPECT_LT(angle_deg(x.normal, want), 1.0) << x.position.transpose();
    curvature.push_back(x.curvature);
  }
  ASSERT_GT(on_faces, 200);
  EXPECT_NEAR(quantile(curvature, 0.5), 0.0, 1.0);
  EXPECT_LT(quantile(curvature, 0.95), 5.0);  // a quarter of the sphere's 20 /m below
}

// The two together: what S4 relies on (convex above flat).
TEST(ModelSurface, SphereIsMoreConvexThanABoxFace) {
  const Octree sphere = test::voxelise(test::sphere_sdf(Eigen::Vector3d::Zero(), 0.04), kCube, 6);
  const Octree box = test::voxelise(test::box_sdf(Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(0.08)), kCube, 6);
  auto median = [](const ModelSurface& s) {
    std::vector<double> k;
    for (const auto& x : s.samples) k.push_back(x.curvature);
    return quantile(k, 0.5);
  };
  EXPECT_GT(median(model_surface(sphere)), 10 * std::max(1.0, std::abs(median(model_surface(box)))));
}

TEST(ModelSurface, CylinderSideNormalsAreRadial) {
  const Octree model = test::voxelise(test::cylinder_sdf(0.035, -0.06, 0.12), kCube, 6);
  const ModelSurface s = model_surface(model);
  int side = 0;
  std::vector<double> curvature;
  for (const auto& x : s.samples) {
    if (std::abs(x.position.z()) > 0.06 - 2 * s.radius) continue;
    ++side;
    const Eigen::Vector3d radial(x.position.x(), x.position.y(), 0);
    EXPECT_LT(angle_deg(x.normal, radial), 12.0) << x.position.transpose();
    curvature.push_back(x.curvature);
  }
  EXPECT_GT(side, 300);
  // Mean curvature of a cylinder's side: 1/(2r) = 14 /m, convex.
  EXPECT_NEAR(quantile(curvature, 0.5), 1 / 0.07, 0.4 / 0.07);
  EXPECT_GT(quantile(curvature, 0.1), 0.0);
  std::printf("cylinder side curvature: 10%% %.1f, median %.1f, 90%% %.1f /m\n", quantile(curvature, 0.1),
              quantile(curvature, 0.5), quantile(curvature, 0.9));
}

TEST(ModelSurface, LeavesCoarserThanTheMaxDepthAreUncertain) {
  // The upper half resolved to depth 4 only, in a model whose max depth is 6.
  const Octree model =
      test::voxelise(test::sphere_sdf(Eigen::Vector3d::Zero(), 0.05), kCube, 6, [](const Eigen::Vector3d& c) { return c.z() > 0.01 ? 4 : 6; });
  const ModelSurface s = model_surface(model);
  int upper = 0, lower = 0;
  for (const auto& x : s.samples) {
    if (x.position.z() > 0.03) {
      ++upper;
      EXPECT_TRUE(x.uncertain) << x.position.transpose();
    } else if (x.position.z() < -0.01) {
      ++lower;
      EXPECT_FALSE(x.uncertain) << x.position.transpose();
    }
  }
  EXPECT_GT(upper, 10);
  EXPECT_GT(lower, 100);
}

// A silhouette pins the surface only where its line of sight grazes it: a sample counts as
// observed when two views graze it along different lines, and stays uncertain when one view, or
// none, does (the far side of an object seen from one side).
TEST(ModelSurface, OnlySamplesTwoViewsGrazeAreObserved) {
  // A sample on the +x side of an object, outward normal +x.
  const SurfaceSample side{{0.05, 0, 0}, {1, 0, 0}};
  auto observed = [&](std::vector<Eigen::Vector3d> eyes) {
    std::vector<SurfaceSample> s{side};
    mark_unobserved(s, eyes);
    return !s[0].uncertain;
  };
  // Two cameras in the tangent plane x = 0.05, lines of sight 90 degrees apart: pinned.
  EXPECT_TRUE(observed({{0.05, 0.3, 0}, {0.05, 0, 0.3}}));
  // One grazing camera only, or two along the same line: a tangent line, not a point.
  EXPECT_FALSE(observed({{0.05, 0.3, 0}}));
  EXPECT_FALSE(observed({{0.05, 0.3, 0}, {0.05, -0.3, 0}}));
  // Cameras facing the sample (or behind it) see its face, not its rim.
  EXPECT_FALSE(observed({{0.4, 0, 0}, {0.3, 0.2, 0.1}, {-0.3, 0, 0}}));
  // Within rim_deg (15 by default) of the tangent plane still grazes.
  EXPECT_TRUE(observed({{0.05 + 0.3 * std::tan(10 * kPi / 180), 0.3, 0}, {0.05, 0, 0.3}}));
  // Already uncertain stays uncertain.
  std::vector<SurfaceSample> s{side};
  s[0].uncertain = true;
  mark_unobserved(s, std::vector<Eigen::Vector3d>{{0.05, 0.3, 0}, {0.05, 0, 0.3}});
  EXPECT_TRUE(s[0].uncertain);
  EXPECT_THROW(mark_unobserved(s, std::vector<Eigen::Vector3d>{}, 0.0), std::invalid_argument);
}

// Carving keeps what no view saw: here a block above the object that no view had in its image,
// and the silhouettes' cone under the table (the object box reaches down to z = -0.02). On a
// table at z = 0, the object is what rests on it, above it.
TEST(ModelSurface, OnATableTheObjectIsWhatRestsOnIt) {
  const Eigen::AlignedBox3d workspace(Eigen::Vector3d(-0.1, -0.1, -0.02), Eigen::Vector3d(0.1, 0.1, 0.18));
  const test::Sdf object = test::box_sdf({0, 0, 0.02}, {0.06, 0.06, 0.08});  // z -0.02 .. 0.06
  const test::Sdf above = test::box_sdf({0, 0, 0.14}, {0.08, 0.08, 0.04});   // z 0.12 .. 0.16
  const Octree model = test::voxelise([&](const Eigen::Vector3d& p) { return std::min(object(p), above(p)); }, workspace, 6);
  auto count = [](const ModelSurface& s, auto&& where) {
    return std::count_if(s.samples.begin(), s.samples.end(), [&](const SurfaceSample& x) { return where(x.position.z()); });
  };
  const ModelSurface all = model_surface(model);
  EXPECT_EQ(all.unsupported_leaves, 0u);
  EXPECT_GT(count(all, [](double z) { return z > 0.11; }), 100);
  EXPECT_GT(count(all, [](double z) { return z < -0.005; }), 50);

  ModelSurfaceParams params;
  params.table_z = 0.0;
  const ModelSurface s = model_surface(model, params);
  EXPECT_GT(s.unsupported_leaves, 0u);  // the block above: nothing joins it to the table
  EXPECT_EQ(s.leaves, all.leaves);
  EXPECT_GT(count(s, [](double z) { return z > 0.055; }), 100);  // the object's top face
  EXPECT_EQ(count(s, [](double z) { return z > 0.07; }), 0);
  EXPECT_EQ(count(s, [](double z) { return z < 0.0; }), 0);
  // The object's sides are as without the table.
  EXPECT_EQ(count(s, [](double z) { return z > 0.01 && z < 0.05; }), count(all, [](double z) { return z > 0.01 && z < 0.05; }));
}

TEST(ModelSurface, AnEmptyModelHasNoSurface) {
  Octree empty;
  empty.bounds = kCube;
  empty.max_depth = 6;
  empty.root.set_state(NodeState::Empty);
  const ModelSurface s = model_surface(empty);
  EXPECT_TRUE(s.samples.empty());
  EXPECT_EQ(s.leaves, 0u);
  Octree none;  // no tree yet
  none.node_count = 0;
  EXPECT_TRUE(model_surface(none).samples.empty());
}

TEST(ModelSurface, AFullRootIsOneBlock) {
  Octree full;
  full.bounds = kCube;
  full.max_depth = 0;
  full.root.set_state(NodeState::Full);
  const ModelSurface s = model_surface(full);
  ASSERT_EQ(s.samples.size(), 1u);
  EXPECT_NEAR(s.samples[0].normal.norm(), 1.0, 1e-12);
}

TEST(ModelSurface, ARootBoxThatIsNotACubeIsAClearError) {
  Octree t;
  t.bounds = Eigen::AlignedBox3d(Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 1, 2));
  try {
    model_surface(t);
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("must be a cube"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace fba::grasp
