#include <array>
#include <cmath>
#include <map>
#include <string>
#include <vector>
#include <numbers>

#include <gtest/gtest.h>

#include "fba/geometry/mesh_io.hpp"
#include "fba/geometry/voxelize.hpp"
#include "support/geometry_checks.hpp"

namespace fba::geometry {
namespace {

const Eigen::AlignedBox3d kUnitCube(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 1));

TEST(Voxelize, SphereVolumeMatchesAnalytic) {
  const double r = 0.8;
  const TriangleMesh sphere = make_uv_sphere({0.03, -0.02, 0.01}, r, 128, 64);
  const VoxelGrid g = voxelize(sphere, kUnitCube, 6);
  EXPECT_EQ(g.n, 64);
  const double analytic = 4.0 / 3.0 * std::numbers::pi * r * r * r;
  EXPECT_NEAR(g.occupied_volume() / analytic, 1.0, 0.01);
  // The centre voxel is in, the corners are out.
  EXPECT_TRUE(g.occupied(32, 32, 32));
  EXPECT_FALSE(g.occupied(0, 0, 0));
  EXPECT_FALSE(g.occupied(63, 63, 63));
}

TEST(Voxelize, BoxGivesExactlyTheVoxelsWhoseCentresAreInside) {
  const Eigen::Vector3d lo(-0.53, -0.21, 0.07), hi(0.44, 0.69, 0.91);
  const VoxelGrid g = voxelize(make_box(lo, hi), kUnitCube, 5);
  std::size_t mismatches = 0, inside = 0;
  for (int k = 0; k < g.n; ++k)
    for (int j = 0; j < g.n; ++j)
      for (int i = 0; i < g.n; ++i) {
        const Eigen::Vector3d c = g.centre(i, j, k);
        const bool in = (c.array() > lo.array()).all() && (c.array() < hi.array()).all();
        inside += in;
        mismatches += in != g.occupied(i, j, k);
      }
  EXPECT_EQ(mismatches, 0u);
  EXPECT_EQ(g.count(), inside);
  EXPECT_GT(inside, 1000u);
}

TEST(Voxelize, RaysThroughSharedEdgesAndVerticesCountOnce) {
  // A box whose faces' diagonals and corners lie exactly on voxel-centre lines: with depth 2 on
  // [-1, 1], the centre lines are at -0.75, -0.25, 0.25, 0.75. Double or missed crossings would
  // flip whole columns.
  const Eigen::Vector3d lo(-0.75, -0.75, -0.6), hi(0.75, 0.75, 0.6);
  const VoxelGrid g = voxelize(make_box(lo, hi), kUnitCube, 2);
  // Column lines at x or y = +-0.75 run along the box's side faces and edges: those voxels are
  // on the boundary and either answer is fine; the inner 2x2 columns must be exactly right.
  for (int j = 1; j <= 2; ++j)
    for (int i = 1; i <= 2; ++i)
      for (int k = 0; k < 4; ++k) {
        const bool in = std::abs(g.centre(i, j, k).z()) < 0.6;
        EXPECT_EQ(g.occupied(i, j, k), in) << i << j << k;
      }
}

TEST(Voxelize, TablePlaneClipDropsVoxelsBelow) {
  const TriangleMesh sphere = make_uv_sphere({0, 0, 0}, 0.8, 64, 32);
  const VoxelGrid full = voxelize(sphere, kUnitCube, 5);
  const VoxelGrid clipped = voxelize(sphere, kUnitCube, 5, 0.1);
  std::size_t expected = 0;
  for (int k = 0; k < full.n; ++k)
    for (int j = 0; j < full.n; ++j)
      for (int i = 0; i < full.n; ++i) {
        const bool keep = full.occupied(i, j, k) && full.centre(i, j, k).z() >= 0.1;
        expected += keep;
        EXPECT_EQ(clipped.occupied(i, j, k), keep);
      }
  EXPECT_EQ(clipped.count(), expected);
  EXPECT_LT(clipped.count(), full.count() / 2);
}

class YcbVoxels : public ::testing::TestWithParam<const char*> {};

TEST_P(YcbVoxels, VolumeMatchesMeshSignedVolume) {
  const TriangleMesh mesh = load_mesh(test::ycb_mesh(GetParam()));
  const auto cube = cube_around(mesh_bounds(mesh), 0.05);
  const VoxelGrid g = voxelize(mesh, cube, 7);
  const double v = signed_volume(mesh);
  ASSERT_GT(v, 0);
  // At 128^3 the boundary error of a compact object is a few percent at most.
  EXPECT_NEAR(g.occupied_volume() / v, 1.0, 0.03) << g.count() << " voxels";
  // Consistency of the three ray directions: each single axis agrees with the majority almost
  // everywhere (a leaky mesh would give streaks along one axis); tested through the volume of a
  // coarser grid too.
  const VoxelGrid coarse = voxelize(mesh, cube, 6);
  EXPECT_NEAR(coarse.occupied_volume() / v, 1.0, 0.06);
}

INSTANTIATE_TEST_SUITE_P(Ycb, YcbVoxels, ::testing::ValuesIn(test::kYcbNames));

VoxelGrid grid_with(int n, std::initializer_list<std::array<int, 3>> cells) {
  VoxelGrid g(kUnitCube, n);
  for (const auto& c : cells) g.set(c[0], c[1], c[2]);
  return g;
}

TEST(VoxelMetrics, IouAndCarvedAwayOnHandMadeGrids) {
  const VoxelGrid truth = grid_with(4, {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {1, 1, 1}});
  const VoxelGrid model = grid_with(4, {{1, 0, 0}, {2, 0, 0}, {1, 1, 1}, {3, 3, 3}, {0, 3, 0}});
  // Intersection 3, union 6.
  EXPECT_DOUBLE_EQ(iou(truth, model), 0.5);
  EXPECT_DOUBLE_EQ(iou(model, truth), 0.5);
  EXPECT_EQ(carved_away(truth, model), 1u);  // (0,0,0)
  EXPECT_EQ(carved_away(model, truth), 2u);
  EXPECT_DOUBLE_EQ(iou(truth, truth), 1.0);
  EXPECT_EQ(carved_away(truth, truth), 0u);
  EXPECT_DOUBLE_EQ(iou(VoxelGrid(kUnitCube, 4), VoxelGrid(kUnitCube, 4)), 1.0);
  EXPECT_DOUBLE_EQ(iou(truth, VoxelGrid(kUnitCube, 4)), 0.0);
  EXPECT_THROW(iou(truth, VoxelGrid(kUnitCube, 8)), std::invalid_argument);
  const Eigen::AlignedBox3d shifted(Eigen::Vector3d(0, -1, -1), Eigen::Vector3d(2, 1, 1));
  EXPECT_THROW(carved_away(truth, VoxelGrid(shifted, 4)), std::invalid_argument);
}

TEST(VoxelMetrics, RasterizedOctreeFillsOccupiedLeavesAtFinestResolution) {
  // Root [-1, 1]^3, max depth 2 (4^3 voxels). Child 0 (x-, y-, z-) is a Full leaf: 2x2x2 voxels.
  // Child 7 (x+, y+, z+) is subdivided; of its children only the outermost one is Partial, the
  // rest Empty. All other depth-1 children are Empty leaves.
  Octree tree;
  tree.bounds = kUnitCube;
  tree.max_depth = 2;
  OctreeNode* c = tree.split(tree.root, NodeState::Empty);
  c[0].set_state(NodeState::Full);
  c[7].set_state(NodeState::Partial);
  OctreeNode* g7 = tree.split(c[7], NodeState::Empty);
  g7[7].set_state(NodeState::Partial);
  const VoxelGrid g = rasterize_octree(tree);
  ASSERT_EQ(g.n, 4);
  EXPECT_EQ(g.count(), 9u);
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) EXPECT_TRUE(g.occupied(i, j, k));
  EXPECT_TRUE(g.occupied(3, 3, 3));
  EXPECT_FALSE(g.occupied(2, 2, 2));
  EXPECT_FALSE(g.occupied(2, 3, 3));
}

TEST(VoxelMetrics, GridMeshIsClosedAndVoxelisesBackToTheGrid) {
  const VoxelGrid g = voxelize(make_uv_sphere({0.1, 0, -0.1}, 0.6, 48, 24), kUnitCube, 4);
  const TriangleMesh m = grid_to_mesh(g);
  EXPECT_NEAR(signed_volume(m), g.occupied_volume(), 1e-5);
  const VoxelGrid again = voxelize(m, kUnitCube, 4);
  EXPECT_EQ(iou(g, again), 1.0);
}

}  // namespace
}  // namespace fba::geometry

namespace fba::geometry {
namespace {

// The corners of each square in the order add_lattice_square asks for them, and its two triangles.
TEST(LatticeSquare, CornersGoAcrossTheOtherTwoAxesAndTheTrianglesFaceDir) {
  for (int axis = 0; axis < 3; ++axis)
    for (int dir : {-1, 1}) {
      SCOPED_TRACE("axis " + std::to_string(axis) + ", dir " + std::to_string(dir));
      TriangleMesh mesh;
      std::vector<Eigen::Vector3i> asked;
      const int origin[3] = {1, 2, 3};
      add_lattice_square(mesh, axis, dir, 7, origin, 2, [&](const int p[3]) {
        asked.emplace_back(p[0], p[1], p[2]);
        mesh.vertices.emplace_back(p[0], p[1], p[2]);
        return static_cast<int>(mesh.vertices.size()) - 1;
      });
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      Eigen::Vector3i base(1, 2, 3);
      base[axis] = 7;
      const Eigen::Vector3i eu = 2 * Eigen::Vector3i::Unit(u), ev = 2 * Eigen::Vector3i::Unit(v);
      const std::vector<Eigen::Vector3i> expected{base, base + eu, base + eu + ev, base + ev};
      EXPECT_EQ(asked, expected);
      ASSERT_EQ(mesh.triangles.size(), 2u);
      double area = 0;
      for (const auto& t : mesh.triangles) {
        const Eigen::Vector3f a = mesh.vertices[t[0]], b = mesh.vertices[t[1]], c = mesh.vertices[t[2]];
        const Eigen::Vector3f n = (b - a).cross(c - a);
        EXPECT_TRUE(n.normalized().isApprox(static_cast<float>(dir) * Eigen::Vector3f::Unit(axis))) << n.transpose();
        area += n.norm() / 2;
      }
      EXPECT_DOUBLE_EQ(area, 4.0);
    }
}

// Welded corners: two squares side by side share the two corners of their common edge.
TEST(LatticeSquare, AWeldingVertexFunctionSharesCornersBetweenSquares) {
  TriangleMesh mesh;
  std::map<std::array<int, 3>, int> index;
  const auto vertex = [&](const int p[3]) {
    const auto [it, added] = index.emplace(std::array<int, 3>{p[0], p[1], p[2]}, static_cast<int>(mesh.vertices.size()));
    if (added) mesh.vertices.emplace_back(p[0], p[1], p[2]);
    return it->second;
  };
  const int left[3] = {0, 0, 0}, right[3] = {1, 0, 0};
  add_lattice_square(mesh, 2, 1, 0, left, 1, vertex);
  add_lattice_square(mesh, 2, 1, 0, right, 1, vertex);
  EXPECT_EQ(mesh.vertices.size(), 6u);
  EXPECT_EQ(mesh.triangles.size(), 4u);
}

TEST(VoxelizeLattice, RecoversGridFromItsSurfaceEvenWithFacesInsideTheSolid) {
  VoxelGrid g = voxelize(make_uv_sphere({0.1, 0, -0.1}, 0.6, 48, 24), kUnitCube, 4);
  TriangleMesh m = grid_to_mesh(g);
  const std::size_t faces_before = m.triangles.size();
  // Add a stray square face inside the solid (as an octree writer emits for a big leaf against
  // smaller ones): lattice plane x = 8 (the middle), square (y 7..8, z 7..8).
  const double h = g.voxel_size();
  // Returns a vector, not an Eigen expression that would refer to a destroyed temporary.
  auto lattice = [&](int i, int j, int k) -> Eigen::Vector3f {
    return (kUnitCube.min() + h * Eigen::Vector3d(i, j, k)).cast<float>();
  };
  const int base = static_cast<int>(m.vertices.size());
  m.vertices.push_back(lattice(8, 7, 7));
  m.vertices.push_back(lattice(8, 8, 7));
  m.vertices.push_back(lattice(8, 8, 8));
  m.vertices.push_back(lattice(8, 7, 8));
  m.triangles.emplace_back(base, base + 1, base + 2);
  m.triangles.emplace_back(base, base + 2, base + 3);
  ASSERT_GT(m.triangles.size(), faces_before);
  ASSERT_TRUE(g.occupied(7, 7, 7) && g.occupied(8, 7, 7));
  const VoxelGrid again = voxelize_lattice_surface(m, kUnitCube, 4);
  EXPECT_EQ(iou(g, again), 1.0);
  EXPECT_EQ(again.count(), g.count());
}

TEST(VoxelizeLattice, RejectsFacesOffTheLattice) {
  EXPECT_THROW(voxelize_lattice_surface(make_uv_sphere({0, 0, 0}, 0.5, 8, 4), kUnitCube, 4),
               std::invalid_argument);
  // A box on the lattice (depth 2: lattice planes at -1, -0.5, 0, 0.5, 1) is fine.
  const VoxelGrid g = voxelize_lattice_surface(make_box({-0.5, -0.5, 0}, {0.5, 1, 0.5}), kUnitCube, 2);
  EXPECT_EQ(g.count(), 2u * 3u * 1u);
}

}  // namespace
}  // namespace fba::geometry
