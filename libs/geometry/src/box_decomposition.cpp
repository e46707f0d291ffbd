#include "fba/geometry/box_decomposition.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

#include "fba/geometry/mesh_io.hpp"

namespace fba::geometry {

namespace {

// The finest grids decompose_into_boxes builds: 2^7 voxels along an axis for the boxes, 2^8 for
// the measure (16.7 million voxels, 16 MiB of occupancy), so that the measure is always finer.
constexpr int kMaxDepth = 7;
constexpr int kMaxMeasureDepth = 8;

}  // namespace

namespace {

// The greedy merge growing each box along the axes in `order` (a permutation of 0, 1, 2), from
// each voxel not yet in a box. With `overlap`, a box grows over every occupied voxel, in a box or
// not (a cover); without, over those in none (a partition).
std::vector<VoxelBox> merge_in_order(const VoxelGrid& grid, const std::array<int, 3>& order, bool overlap) {
  const int n = grid.n;
  std::vector<std::uint8_t> free(grid.occupancy);  // occupied and not yet in a box
  const std::vector<std::uint8_t>& room = overlap ? grid.occupancy : free;  // where a box may grow
  // Whether every voxel of [lo, hi) is room.
  auto all_free = [&](const Eigen::Vector3i& lo, const Eigen::Vector3i& hi) {
    for (int k = lo.z(); k < hi.z(); ++k)
      for (int j = lo.y(); j < hi.y(); ++j)
        for (int i = lo.x(); i < hi.x(); ++i)
          if (!room[grid.index(i, j, k)]) return false;
    return true;
  };
  std::vector<VoxelBox> boxes;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        if (!free[grid.index(i, j, k)]) continue;
        VoxelBox b{Eigen::Vector3i(i, j, k), Eigen::Vector3i(i + 1, j + 1, k + 1)};
        for (const int axis : order) {
          // Grow by one slab at a time while the whole slab is free.
          for (;;) {
            if (b.max[axis] >= n) break;
            Eigen::Vector3i lo = b.min, hi = b.max;
            lo[axis] = b.max[axis];
            hi[axis] = b.max[axis] + 1;
            if (!all_free(lo, hi)) break;
            ++b.max[axis];
          }
        }
        for (int kk = b.min.z(); kk < b.max.z(); ++kk)
          for (int jj = b.min.y(); jj < b.max.y(); ++jj)
            for (int ii = b.min.x(); ii < b.max.x(); ++ii) free[grid.index(ii, jj, kk)] = 0;
        boxes.push_back(b);
      }
  return boxes;
}

// Of the six orders of the axes, the one that gives the fewest boxes.
std::vector<VoxelBox> fewest(const VoxelGrid& grid, bool overlap) {
  std::vector<VoxelBox> best;
  std::array<int, 3> order{0, 1, 2};
  do {
    std::vector<VoxelBox> boxes = merge_in_order(grid, order, overlap);
    if (best.empty() || boxes.size() < best.size()) best = std::move(boxes);
  } while (std::next_permutation(order.begin(), order.end()));
  return best;
}

}  // namespace

std::vector<VoxelBox> merge_into_boxes(const VoxelGrid& grid) { return fewest(grid, false); }

std::vector<VoxelBox> cover_with_boxes(const VoxelGrid& grid) {
  std::vector<VoxelBox> boxes = fewest(grid, true);
  // A box the others cover whole adds nothing: dropped, the largest kept first.
  std::stable_sort(boxes.begin(), boxes.end(), [](const VoxelBox& a, const VoxelBox& b) { return a.voxels() > b.voxels(); });
  std::vector<int> count(grid.occupancy.size(), 0);
  auto each = [&](const VoxelBox& b, const auto& f) {
    for (int k = b.min.z(); k < b.max.z(); ++k)
      for (int j = b.min.y(); j < b.max.y(); ++j)
        for (int i = b.min.x(); i < b.max.x(); ++i) f(grid.index(i, j, k));
  };
  for (const VoxelBox& b : boxes) each(b, [&](std::size_t v) { ++count[v]; });
  std::vector<VoxelBox> kept;
  for (auto it = boxes.rbegin(); it != boxes.rend(); ++it) {  // the smallest first
    bool redundant = true;
    each(*it, [&](std::size_t v) { redundant = redundant && count[v] > 1; });
    if (redundant) each(*it, [&](std::size_t v) { --count[v]; });
    else kept.push_back(*it);
  }
  std::reverse(kept.begin(), kept.end());
  return kept;
}

Eigen::AlignedBox3d world_box(const VoxelGrid& grid, const VoxelBox& box) {
  const double h = grid.voxel_size();
  return {grid.bounds.min() + h * box.min.cast<double>(), grid.bounds.min() + h * box.max.cast<double>()};
}

BoxDecomposition decompose_into_boxes(const TriangleMesh& mesh, double voxel_size, int measure_refine) {
  if (mesh.triangles.empty()) throw std::invalid_argument("box decomposition: the mesh has no triangles");
  if (!(voxel_size > 0) || !std::isfinite(voxel_size))
    throw std::invalid_argument("box decomposition: the voxel size must be a positive length, found " + std::to_string(voxel_size));
  if (measure_refine != 2 && measure_refine != 4)
    throw std::invalid_argument("box decomposition: measure_refine must be 2 or 4, found " + std::to_string(measure_refine));
  const Eigen::AlignedBox3d bounds = mesh_bounds(mesh);
  const double extent = bounds.sizes().maxCoeff();
  int depth = 0;
  while (depth <= kMaxDepth && voxel_size * double(1 << depth) < extent) ++depth;
  if (depth > kMaxDepth)
    throw std::invalid_argument("box decomposition: a " + std::to_string(extent) + " m object in voxels of " + std::to_string(voxel_size) +
                                " m needs more than " + std::to_string(1 << kMaxDepth) + " along an axis; give larger voxels");
  // The lattice starts at the mesh's lowest corner: the bottom layer's voxels end at its lowest z.
  const Eigen::Vector3d side = Eigen::Vector3d::Constant(voxel_size * double(1 << depth));
  const Eigen::AlignedBox3d cube(bounds.min(), bounds.min() + side);

  BoxDecomposition out;
  out.voxel_size = voxel_size;
  out.grid = voxelize(mesh, cube, depth);
  for (const VoxelBox& b : cover_with_boxes(out.grid)) out.boxes.push_back(world_box(out.grid, b));
  out.volume = out.grid.occupied_volume();
  // The solid's mass properties, voxel by voxel (the boxes overlap: their own would count twice).
  const double h = out.grid.voxel_size();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();  // sum of p p^T
  std::size_t count = 0;
  for (int k = 0; k < out.grid.n; ++k)
    for (int j = 0; j < out.grid.n; ++j)
      for (int i = 0; i < out.grid.n; ++i)
        if (out.grid.occupied(i, j, k)) {
          const Eigen::Vector3d p = out.grid.centre(i, j, k);
          sum += p;
          second += p * p.transpose();
          ++count;
        }
  if (count > 0) {
    out.centroid = sum / double(count);
    // Per unit mass, about the centroid: each voxel a point at its centre plus its own cube's h^2/6.
    const Eigen::Matrix3d covariance = second / double(count) - out.centroid * out.centroid.transpose();
    out.inertia = covariance.trace() * Eigen::Matrix3d::Identity() - covariance + Eigen::Matrix3d::Identity() * (h * h / 6);
  }
  out.mesh_volume = std::abs(signed_volume(mesh));

  // The fit, on a finer grid of the same cube: a fine voxel is in the boxes when its coarse voxel
  // is occupied (the fine lattice refines the coarse one).
  const int refine_depth = std::min(measure_refine == 4 ? 2 : 1, kMaxMeasureDepth - depth);
  const VoxelGrid fine = voxelize(mesh, cube, depth + refine_depth);
  out.measure_voxel_size = fine.voxel_size();
  std::size_t both = 0, either = 0;
  for (int k = 0; k < fine.n; ++k)
    for (int j = 0; j < fine.n; ++j)
      for (int i = 0; i < fine.n; ++i) {
        const bool in_boxes = out.grid.occupied(i >> refine_depth, j >> refine_depth, k >> refine_depth);
        const bool in_mesh = fine.occupied(i, j, k);
        both += in_boxes && in_mesh;
        either += in_boxes || in_mesh;
      }
  out.iou = either == 0 ? 1.0 : double(both) / double(either);
  return out;
}

}  // namespace fba::geometry
