// ModelObstacles' boxes and their bounding-volume hierarchy, for RobotCollision.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <fcl/narrowphase/collision_object.h>

#include "fba/motion/model_obstacles.hpp"

namespace fba::motion {

struct ModelObstacles::Impl {
  std::vector<Eigen::AlignedBox3d> boxes;
  // One FCL object per box, for the exact test once the hierarchy has narrowed a body to it.
  std::vector<std::unique_ptr<fcl::CollisionObjectd>> objects;

  // A binary tree over the boxes, each node bounded by the ball round its boxes' bounds. A query
  // tests a body against a node's ball and descends only where it may touch: a long slanted arm
  // link's axis-aligned bounds (what an AABB tree culls by) hold thousands of leaves it passes
  // far from, which the ball test drops a whole subtree at a time.
  struct Node {
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    double radius = 0;
    std::uint32_t first = 0, count = 0;  // a leaf: order[first, first + count); else count == 0
    std::uint32_t right = 0;             // not a leaf: the second child (the first follows the node)
  };
  std::vector<Node> nodes;
  std::vector<std::uint32_t> order;  // box indices, each leaf's a contiguous run

  // Visits the boxes whose node balls `may_touch(centre, radius)` accepts, down to the leaves,
  // calling `box(index)` for each box there; `box` returns true to stop the query.
  template <class MayTouch, class Box>
  bool visit(const MayTouch& may_touch, const Box& box) const {
    if (nodes.empty()) return false;
    std::uint32_t stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& n = nodes[stack[--top]];
      if (!may_touch(n.centre, n.radius)) continue;
      if (n.count > 0) {
        for (std::uint32_t k = n.first; k < n.first + n.count; ++k)
          if (box(order[k])) return true;
        continue;
      }
      const auto self = static_cast<std::uint32_t>(&n - nodes.data());
      stack[top++] = n.right;
      stack[top++] = self + 1;
    }
    return false;
  }
};

}  // namespace fba::motion
