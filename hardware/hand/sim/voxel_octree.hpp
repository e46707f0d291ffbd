// The voxelised object as an octree, for the lift test's own reach planning.
#pragma once

#include <functional>
#include <memory>
#include <vector>

#include "fba/geometry/voxelize.hpp"
#include "fba/types/octree.hpp"

namespace fba::sim_hand {

// An octree of the voxelised object: a node whose voxels are all occupied is Full, all empty
// Empty; the rest split. What a perfect carve would give reach planning as its model.
inline Octree octree_of(const geometry::VoxelGrid& g) {
  const int n = g.n;
  int depth = 0;
  while ((1 << depth) < n) ++depth;
  // Summed-volume table: the occupied voxels in [0, i) x [0, j) x [0, k).
  const auto m = static_cast<std::size_t>(n + 1);
  std::vector<int> sum(m * m * m, 0);
  auto at = [&](int i, int j, int k) -> int& { return sum[(std::size_t(k) * m + std::size_t(j)) * m + std::size_t(i)]; };
  for (int k = 1; k <= n; ++k)
    for (int j = 1; j <= n; ++j)
      for (int i = 1; i <= n; ++i)
        at(i, j, k) = int(g.occupied(i - 1, j - 1, k - 1)) + at(i - 1, j, k) + at(i, j - 1, k) + at(i, j, k - 1) - at(i - 1, j - 1, k) -
                      at(i - 1, j, k - 1) - at(i, j - 1, k - 1) + at(i - 1, j - 1, k - 1);
  auto count = [&](int i, int j, int k, int s) {
    return at(i + s, j + s, k + s) - at(i, j + s, k + s) - at(i + s, j, k + s) - at(i + s, j + s, k) + at(i, j, k + s) + at(i, j + s, k) +
           at(i + s, j, k) - at(i, j, k);
  };
  Octree t;
  t.bounds = g.bounds;
  t.max_depth = depth;
  t.views = 1;
  t.arena = std::make_shared<OctreeArena>();
  std::function<void(OctreeNode&, int, int, int, int)> build = [&](OctreeNode& node, int d, int i, int j, int k) {
    const int s = n >> d;
    const int c = count(i, j, k, s);
    if (c == 0) return node.set_state(NodeState::Empty);
    if (c == s * s * s) return node.set_state(NodeState::Full);
    node.set_state(NodeState::Partial);
    OctreeNode* kids = t.split(node, NodeState::Partial);
    const int h = s / 2;
    for (int q = 0; q < 8; ++q) build(kids[q], d + 1, i + (q & 1 ? h : 0), j + (q & 2 ? h : 0), k + (q & 4 ? h : 0));
  };
  build(t.root, 0, 0, 0, 0);
  return t;
}

}  // namespace fba::sim_hand
