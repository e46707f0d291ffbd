// The carved model as obstacles: every leaf of the octree that is not carved away, occupied or
// not yet carved alike, as a box, in a tree of bounding balls (src/model_obstacles_impl.hpp) with
// FCL's exact test at its leaves. Built once per model and shared by the checks made against it;
// immutable, so several checkers may read it at once.
#pragma once

#include <cstddef>
#include <memory>

#include <Eigen/Geometry>

#include "fba/types/octree.hpp"

namespace fba::motion {

class RobotCollision;

class ModelObstacles {
 public:
  explicit ModelObstacles(const Octree& model);
  ~ModelObstacles();
  ModelObstacles(const ModelObstacles&) = delete;
  ModelObstacles& operator=(const ModelObstacles&) = delete;

  std::size_t size() const;                       // the boxes
  const Eigen::AlignedBox3d& box(std::size_t i) const;

  struct Impl;  // src/model_obstacles_impl.hpp

 private:
  friend class RobotCollision;
  std::unique_ptr<Impl> impl_;
};

}  // namespace fba::motion
