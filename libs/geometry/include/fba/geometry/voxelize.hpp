// Dense voxel grids: the true solid voxelisation of a mesh, an octree model rasterised at its
// finest resolution, and the accuracy metrics that compare them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Geometry>

#include "fba/types/mesh.hpp"
#include "fba/types/octree.hpp"

namespace fba::geometry {

// n x n x n cubic voxels filling `bounds` (a cube). Voxel (i, j, k) spans
// bounds.min() + [i, i+1) * voxel_size along x (j along y, k along z) and is stored at
// index(i, j, k) = (k * n + j) * n + i; occupancy is 0 or 1.
struct VoxelGrid {
  Eigen::AlignedBox3d bounds;
  int n = 0;
  std::vector<std::uint8_t> occupancy;

  VoxelGrid() = default;
  VoxelGrid(const Eigen::AlignedBox3d& cube, int n_per_axis)
      : bounds(cube), n(n_per_axis), occupancy(static_cast<std::size_t>(n) * n * n, 0) {}

  double voxel_size() const { return bounds.sizes().x() / n; }
  std::size_t index(int i, int j, int k) const {
    return (static_cast<std::size_t>(k) * n + j) * n + i;
  }
  bool occupied(int i, int j, int k) const { return occupancy[index(i, j, k)] != 0; }
  void set(int i, int j, int k, bool value = true) { occupancy[index(i, j, k)] = value ? 1 : 0; }
  Eigen::Vector3d centre(int i, int j, int k) const {
    return bounds.min() + voxel_size() * Eigen::Vector3d(i + 0.5, j + 0.5, k + 0.5);
  }
  std::size_t count() const;                  // occupied voxels
  double occupied_volume() const;             // count * voxel_size^3
  bool same_layout(const VoxelGrid& other) const;  // same n and (numerically) same bounds
};

// The solid voxelisation of a closed mesh: a voxel is occupied when its centre is inside the
// mesh. Inside is decided by ray parity along three lines through the centre, parallel to x, y
// and z, by majority: a ray that slips through a crack or grazes an edge is outvoted by the two
// others. Edge and vertex hits use a consistent tie rule, so a ray through a shared edge counts
// one crossing, not two or zero. Cost ~ (triangles * their footprint + n^3).
// `cube` should be a cube (cube_around()); n = 2^depth. With z_min set, voxels whose centre lies
// below z_min (under a table plane) are cleared.
VoxelGrid voxelize(const TriangleMesh& mesh, const Eigen::AlignedBox3d& cube, int depth,
                   std::optional<double> z_min = std::nullopt);

// The solid enclosed by a surface whose faces all lie on the voxel lattice of (cube, depth):
// a carved octree saved as cubes (PLY), or grid_to_mesh(). Faces become walls between voxels and
// the outside is flood-filled from the grid border; everything it cannot reach is occupied. Unlike
// ray parity this is unaffected by faces inside the solid (e.g. a large leaf's face against
// smaller leaves, which octree writers may emit). Throws std::invalid_argument, naming the
// triangle, when a triangle is not axis-aligned on the lattice (tolerance 1% of a voxel).
VoxelGrid voxelize_lattice_surface(const TriangleMesh& mesh, const Eigen::AlignedBox3d& cube,
                                   int depth);

// Clears every voxel whose centre is below z_min (the table plane clip).
void clip_below(VoxelGrid& grid, double z_min);

// The occupied leaves of an octree (leaf nodes whose state is not Empty) as a grid at the
// octree's finest resolution, 2^max_depth per axis over octree.bounds: a leaf at depth d fills
// 2^(max_depth - d) voxels per axis.
VoxelGrid rasterize_octree(const Octree& octree);

// Intersection over union of the occupied voxels (1 when both are empty). The grids must have
// the same layout (std::invalid_argument otherwise).
double iou(const VoxelGrid& a, const VoxelGrid& b);

// Voxels occupied in `truth` but not in `model`: what a conservative carve must never remove.
std::size_t carved_away(const VoxelGrid& truth, const VoxelGrid& model);

// The boundary of the occupied voxels as a closed mesh of square faces (two triangles each,
// outward), only where an occupied voxel meets an empty one: for rendering and PLY export.
TriangleMesh grid_to_mesh(const VoxelGrid& grid);

// Appends to `mesh` a square face on the integer lattice: in the plane p[axis] = `plane`, from
// `origin` across `size` along the two other axes (u = axis + 1, v = axis + 2, mod 3), as two
// triangles wound counter-clockwise seen from the side `dir` (+1 or -1) points to; the outward face
// of a solid cell on the other side. `vertex(p)` returns the mesh's index of lattice point p (an
// int[3]), adding it or welding it to an earlier one; it is asked for the corners in the order
// origin, +u, +u+v, +v. grid_to_mesh's faces and the carver's octree surface are these squares.
template <class VertexOf>
void add_lattice_square(TriangleMesh& mesh, int axis, int dir, int plane, const int origin[3], int size, VertexOf&& vertex) {
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  const int su[4] = {0, 1, 1, 0}, sv[4] = {0, 0, 1, 1};
  int idx[4];
  for (int q = 0; q < 4; ++q) {
    int p[3];
    p[axis] = plane;
    p[u] = origin[u] + su[q] * size;
    p[v] = origin[v] + sv[q] * size;
    idx[q] = vertex(p);
  }
  // (u, v, axis) is right-handed, so u x v points along +axis: the corners' order faces +dir.
  if (dir > 0) {
    mesh.triangles.emplace_back(idx[0], idx[1], idx[2]);
    mesh.triangles.emplace_back(idx[0], idx[2], idx[3]);
  } else {
    mesh.triangles.emplace_back(idx[0], idx[2], idx[1]);
    mesh.triangles.emplace_back(idx[0], idx[3], idx[2]);
  }
}

}  // namespace fba::geometry
