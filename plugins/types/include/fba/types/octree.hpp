// An immutable snapshot of a carved octree model.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Geometry>

#include "fba/data_type.hpp"

namespace fba {

enum class NodeState : std::uint8_t {
  Empty,    // carved away: outside the object in some view
  Full,     // inside the object's silhouette in every view that sees it whole
  Partial,  // straddles the object's boundary (subdivided, or at the resolution limit)
};

struct OctreeNode {
  Eigen::Vector3f centre;
  float half_size = 0;
  std::uint8_t depth = 0;
  NodeState state = NodeState::Partial;
  std::int32_t first_child = -1;  // index of 8 consecutive children, -1 for a leaf
  float occupancy = 0;            // lowest silhouette occupancy over the views that saw it
  float interest = 0;             // grasp interest that drove its refinement, 0 when none
  bool is_leaf() const { return first_child < 0; }
};

struct Octree {
  Eigen::AlignedBox3d bounds;      // the root voxel (a cube), world coordinates
  int max_depth = 0;
  int views = 0;                   // views integrated so far
  std::vector<OctreeNode> nodes;   // nodes[0] is the root; children are stored contiguously
};

}  // namespace fba

FBA_DATA_TYPE(fba::Octree, "fba.Octree",
              "An immutable octree model: nodes full / empty / partial with depth, bounds, occupancy and grasp interest.");
