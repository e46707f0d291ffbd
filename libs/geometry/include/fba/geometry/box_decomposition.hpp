// A solid as convex pieces for a physics engine: its voxelisation merged greedily into axis-aligned
// boxes. MuJoCo (and most engines) collide a mesh as its convex hull, which fills every concavity;
// the boxes' union is exactly the occupied voxels, so a concavity wider than a voxel stays empty.
// Chosen over an approximate convex decomposition (HACD, V-HACD): the pieces' fit is known in
// advance (a surface off by at most half a voxel's diagonal), the result is the same on every run,
// and boxes are the shapes engines collide fastest and most robustly. A convex solid needs none of
// this: it is its own hull (convex_hull.hpp).
#pragma once

#include <cstddef>
#include <vector>

#include <Eigen/Geometry>

#include "fba/geometry/voxelize.hpp"
#include "fba/types/mesh.hpp"

namespace fba::geometry {

// A box of whole voxels: lattice indices [min, max) along x, y, z.
struct VoxelBox {
  Eigen::Vector3i min = Eigen::Vector3i::Zero();
  Eigen::Vector3i max = Eigen::Vector3i::Zero();
  long voxels() const { return long(max.x() - min.x()) * (max.y() - min.y()) * (max.z() - min.z()); }
};

// The occupied voxels of `grid` as boxes that do not overlap and cover exactly them. Greedy, in
// the grid's index order: from the first voxel not yet covered, a box grown along one axis as far
// as it goes, then along a second by whole slabs, then along the third; of the six orders of the
// axes, the one that gives the fewest boxes.
std::vector<VoxelBox> merge_into_boxes(const VoxelGrid& grid);

// The occupied voxels of `grid` as boxes whose union is exactly them, allowed to overlap: each grown
// as merge_into_boxes grows one but over every occupied voxel, from each voxel no box holds yet;
// then a box the others cover whole is dropped. Far fewer boxes than a partition (a physics
// engine tests each against each part near it, every step).
std::vector<VoxelBox> cover_with_boxes(const VoxelGrid& grid);

// The box in the grid's world coordinates.
Eigen::AlignedBox3d world_box(const VoxelGrid& grid, const VoxelBox& box);

struct BoxDecomposition {
  std::vector<Eigen::AlignedBox3d> boxes;  // world coordinates, the mesh's: cover_with_boxes, overlapping
  VoxelGrid grid;                          // the voxelisation they partition
  double voxel_size = 0;                   // m
  double volume = 0;                       // of the boxes, m^3
  double mesh_volume = 0;                  // of the mesh (divergence theorem), m^3
  // The voxelised solid's mass properties (the boxes overlap, so theirs would count twice): its
  // centroid (world) and its inertia about it per unit mass, m^2.
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
  // Volume intersection over union of the boxes and the mesh's solid, measured on a voxelisation
  // of measure_voxel_size (finer than the boxes', whose lattice it refines).
  double iou = 0;
  double measure_voxel_size = 0;  // m
};

// The mesh (closed, metres) voxelised with cubes of `voxel_size` whose lattice starts at the
// mesh's lowest corner (so a mesh standing on a plane stands on it as boxes too), covered with
// boxes. `measure_refine`: 2 or 4, how much finer the measure's voxels are (at most 256 of them
// along an axis; its cost grows with their cube). Throws std::invalid_argument for an empty mesh,
// a voxel size that is not positive or that gives more than 128 voxels along an axis.
BoxDecomposition decompose_into_boxes(const TriangleMesh& mesh, double voxel_size, int measure_refine = 2);

}  // namespace fba::geometry
