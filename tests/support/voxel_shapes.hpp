// Octree models of shapes whose surface is known, voxelised from a signed distance: a node whose
// centre is farther than its half diagonal from the surface is empty or full; the rest are split
// down to the leaf depth, where a leaf is occupied (Partial, as the carver leaves the boundary)
// when its centre is inside.
#pragma once

#include <cmath>
#include <functional>

#include <Eigen/Geometry>

#include "fba/types/octree.hpp"

namespace fba::grasp::test {

using Sdf = std::function<double(const Eigen::Vector3d&)>;

inline Sdf sphere_sdf(const Eigen::Vector3d& centre, double r) {
  return [=](const Eigen::Vector3d& p) { return (p - centre).norm() - r; };
}
// Axis-aligned box of the given size centred at centre. The max of the slab distances: exact
// inside, a lower bound outside, so a node it calls empty is empty.
inline Sdf box_sdf(const Eigen::Vector3d& centre, const Eigen::Vector3d& size) {
  return [=](const Eigen::Vector3d& p) { return ((p - centre).cwiseAbs() - size / 2).maxCoeff(); };
}
// Upright cylinder (axis z) standing on z = base.
inline Sdf cylinder_sdf(double radius, double base, double height) {
  return [=](const Eigen::Vector3d& p) {
    return std::max(std::hypot(p.x(), p.y()) - radius, std::abs(p.z() - base - height / 2) - height / 2);
  };
}

// leaf_depth(centre) says how deep the boundary is resolved there (at most max_depth), so a test
// can leave parts of a model coarse; views is the model's view count.
inline Octree voxelise(const Sdf& sdf, const Eigen::AlignedBox3d& cube, int max_depth,
                       const std::function<int(const Eigen::Vector3d&)>& leaf_depth = {}, int views = 8) {
  Octree t;
  t.bounds = cube;
  t.max_depth = max_depth;
  t.views = views;
  std::function<void(OctreeNode&, int, const Eigen::Vector3d&, double)> build = [&](OctreeNode& n, int depth,
                                                                                     const Eigen::Vector3d& c, double h) {
    const double d = sdf(c);
    if (d > h * std::sqrt(3.0)) return n.set_state(NodeState::Empty);
    if (d < -h * std::sqrt(3.0)) return n.set_state(NodeState::Full);
    if (depth >= (leaf_depth ? std::min(max_depth, leaf_depth(c)) : max_depth))
      return n.set_state(d <= 0 ? NodeState::Partial : NodeState::Empty);
    n.set_state(NodeState::Partial);
    OctreeNode* k = t.split(n, NodeState::Partial);
    for (int i = 0; i < 8; ++i)
      build(k[i], depth + 1, c + h / 2 * Eigen::Vector3d(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1), h / 2);
  };
  build(t.root, 0, cube.center(), cube.sizes().x() / 2);
  return t;
}

}  // namespace fba::grasp::test
