// The boxes the lift test gives MuJoCo: their union is the voxelisation exactly (a partition, or a
// cover with far fewer boxes), a concavity stays empty, the fit to the mesh is bounded by the voxel
// size, and the solid's mass properties are the voxels'.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "fba/geometry/box_decomposition.hpp"
#include "fba/geometry/mesh_io.hpp"
#include "support/u_shape.hpp"
#include "support/geometry_checks.hpp"

namespace fba::geometry {
namespace {

// Each occupied voxel lies in exactly one box, and no box holds an empty one.
void expect_partition(const VoxelGrid& grid, const std::vector<VoxelBox>& boxes) {
  std::vector<int> covered(grid.occupancy.size(), 0);
  for (const VoxelBox& b : boxes)
    for (int k = b.min.z(); k < b.max.z(); ++k)
      for (int j = b.min.y(); j < b.max.y(); ++j)
        for (int i = b.min.x(); i < b.max.x(); ++i) ++covered[grid.index(i, j, k)];
  for (std::size_t v = 0; v < covered.size(); ++v) ASSERT_EQ(covered[v], grid.occupancy[v] ? 1 : 0) << "voxel " << v;
}

// Each occupied voxel lies in at least one box, no box holds an empty one, and none is covered
// whole by the others.
void expect_cover(const VoxelGrid& grid, const std::vector<VoxelBox>& boxes) {
  std::vector<int> covered(grid.occupancy.size(), 0);
  auto each = [&](const VoxelBox& b, const auto& f) {
    for (int k = b.min.z(); k < b.max.z(); ++k)
      for (int j = b.min.y(); j < b.max.y(); ++j)
        for (int i = b.min.x(); i < b.max.x(); ++i) f(grid.index(i, j, k));
  };
  for (const VoxelBox& b : boxes) each(b, [&](std::size_t v) { ++covered[v]; });
  for (std::size_t v = 0; v < covered.size(); ++v) ASSERT_EQ(covered[v] > 0, grid.occupancy[v] != 0) << "voxel " << v;
  for (const VoxelBox& b : boxes) {
    bool needed = false;
    each(b, [&](std::size_t v) { needed = needed || covered[v] == 1; });
    EXPECT_TRUE(needed) << "a box the others cover whole";
  }
}

TEST(BoxDecomposition, ABoxOnTheLatticeIsOneBoxAndFitsExactly) {
  const TriangleMesh box = make_box({0.01, -0.02, 0}, {0.05, 0.04, 0.10});  // 4 x 6 x 10 cm, whole 1 cm voxels
  const BoxDecomposition d = decompose_into_boxes(box, 0.01);
  ASSERT_EQ(d.boxes.size(), 1u);
  // Within the floats the mesh's vertices are.
  EXPECT_LT((d.boxes[0].min() - Eigen::Vector3d(0.01, -0.02, 0)).norm(), 1e-7);
  EXPECT_LT((d.boxes[0].max() - Eigen::Vector3d(0.05, 0.04, 0.10)).norm(), 1e-7);
  EXPECT_NEAR(d.volume, 0.04 * 0.06 * 0.10, 1e-9);
  EXPECT_NEAR(d.iou, 1.0, 1e-12);
  // A solid box's centroid and inertia per unit mass: (b^2 + c^2) / 12 about each axis.
  EXPECT_LT((d.centroid - Eigen::Vector3d(0.03, 0.01, 0.05)).norm(), 1e-7);
  const Eigen::Vector3d size(0.04, 0.06, 0.10);
  for (int a = 0; a < 3; ++a) {
    const double b = size[(a + 1) % 3], c = size[(a + 2) % 3];
    EXPECT_NEAR(d.inertia(a, a), (b * b + c * c) / 12, 1e-8) << "axis " << a;
  }
  EXPECT_NEAR(d.inertia(0, 1), 0, 1e-10);
}

TEST(BoxDecomposition, TheBoxesPartitionOrCoverTheOccupiedVoxels) {
  const TriangleMesh can = load_mesh(test::ycb_mesh("YcbMasterChefCan"));
  const BoxDecomposition d = decompose_into_boxes(can, 0.003);
  const auto partition = merge_into_boxes(d.grid);
  expect_partition(d.grid, partition);
  const auto cover = cover_with_boxes(d.grid);
  EXPECT_EQ(cover.size(), d.boxes.size());
  expect_cover(d.grid, cover);
  EXPECT_LT(cover.size(), partition.size());  // overlapping, fewer
  // The lattice starts at the mesh's lowest corner: standing on z = 0, the boxes do too.
  double lowest = INFINITY;
  for (const auto& b : d.boxes) lowest = std::min(lowest, b.min().z());
  EXPECT_NEAR(lowest, mesh_bounds(can).min().z(), 1e-9);
}

// The U's walls are boxes; the gap between them, which its convex hull fills, is in none.
TEST(BoxDecomposition, AConcavityWiderThanAVoxelStaysEmpty) {
  const fba::test::UShape u;
  const TriangleMesh mesh = fba::test::make_u_shape(u);
  ASSERT_GT(signed_volume(mesh), 0);
  const double wall_volume = 2 * u.wall * u.height * u.length + (u.width - 2 * u.wall) * u.base * u.length;
  EXPECT_NEAR(signed_volume(mesh), wall_volume, 1e-9);
  const BoxDecomposition d = decompose_into_boxes(mesh, 0.005);
  const Eigen::Vector3d in_gap(0, 0, (u.base + u.height) / 2);
  for (const auto& b : d.boxes) EXPECT_FALSE(b.contains(in_gap)) << "a box reaches into the gap";
  EXPECT_GT(d.iou, 0.99);  // its faces lie on the 5 mm lattice but for the rounding of floats
  EXPECT_NEAR(d.volume, wall_volume, 0.02 * wall_volume);
}

// The boxes' surface lies within half a voxel's diagonal of the mesh's, so what they miss or add
// lies in a band that wide around it: 1 - IoU is at most about the band's volume over the mesh's,
// sqrt(3) * voxel * area / volume. Finer voxels fit better. The YCB meshes' figures are printed.
TEST(BoxDecomposition, TheFitToEachYcbMeshIsBoundedByTheVoxelSize) {
  for (const char* name : test::kYcbNames) {
    const TriangleMesh mesh = load_mesh(test::ycb_mesh(name));
    const double area = surface_area(mesh), volume = std::abs(signed_volume(mesh));
    double previous_iou = 0;
    for (const double voxel : {0.004, 0.002}) {
      const BoxDecomposition d = decompose_into_boxes(mesh, voxel);
      std::printf("%-17s voxel %.1f mm: %4zu boxes (a partition: %4zu), volume %.1f of %.1f cm^3, IoU %.4f (measured on %.1f mm voxels)\n", name,
                  voxel * 1e3, d.boxes.size(), merge_into_boxes(d.grid).size(), d.volume * 1e6, volume * 1e6, d.iou, d.measure_voxel_size * 1e3);
      EXPECT_GE(d.iou, 1 - std::sqrt(3.0) * voxel * area / volume) << name << " at " << voxel;
      EXPECT_GT(d.iou, previous_iou) << name << " at " << voxel;
      previous_iou = d.iou;
    }
  }
}

TEST(BoxDecomposition, ImpossibleRequestsAreRefusedWithTheFigures) {
  const TriangleMesh box = make_box({0, 0, 0}, {0.1, 0.1, 0.1});
  EXPECT_THROW(decompose_into_boxes(TriangleMesh{}, 0.01), std::invalid_argument);
  EXPECT_THROW(decompose_into_boxes(box, 0), std::invalid_argument);
  EXPECT_THROW(decompose_into_boxes(box, 0.01, 3), std::invalid_argument);
  try {
    decompose_into_boxes(box, 0.0001);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("more than 128 along an axis"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace fba::geometry
