// ModelObstacles' FCL objects, for RobotCollision.
#pragma once

#include <memory>
#include <vector>

#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/narrowphase/collision_object.h>

#include "fba/motion/model_obstacles.hpp"

namespace fba::motion {

struct ModelObstacles::Impl {
  std::vector<Eigen::AlignedBox3d> boxes;
  // One object per box, its user data the box's index + 1.
  std::vector<std::unique_ptr<fcl::CollisionObjectd>> objects;
  fcl::DynamicAABBTreeCollisionManagerd tree;
};

}  // namespace fba::motion
