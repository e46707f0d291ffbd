// A box standing on the table in the grasp task's workspace, as a carved model and with a grasp on
// it: the scene reach planning and the whole-robot lift test are tested on.
#pragma once

#include <cmath>

#include <Eigen/Geometry>

#include "fba/types/grasp.hpp"
#include "fba/types/octree.hpp"
#include "support/voxel_shapes.hpp"

namespace fba::test {

// The task's workspace (tasks/grasp.yaml): a 26 cm cube on the table, 4 mm leaves at depth 6.
inline Eigen::AlignedBox3d workspace() { return {Eigen::Vector3d(-0.13, -0.13, -0.02), Eigen::Vector3d(0.13, 0.13, 0.24)}; }

// A box of `size` standing on the table, centred on (x, y), voxelised as a carved model.
inline Octree box_model(const Eigen::Vector3d& size, double x = 0, double y = 0, int depth = 6) {
  return grasp::test::voxelise(grasp::test::box_sdf(Eigen::Vector3d(x, y, size.z() / 2), size), workspace(), depth);
}

// A grasp on a box standing on the table at (x, y): the thumb on the face at -u (in the table's
// plane), the fingers on the face at +u, 2 cm either side, all at height h, the hand coming along
// `approach` (perpendicular to u).
inline Grasp box_grasp(const Eigen::Vector3d& size, const Eigen::Vector3d& u, const Eigen::Vector3d& approach, double h, double x = 0,
                       double y = 0) {
  const Eigen::Vector3d centre(x, y, h);
  const double half = std::abs(u.dot(size)) / 2;
  const Eigen::Vector3d side = approach.cross(u).normalized();
  Grasp g;
  g.contacts[0] = {centre - u * half, u};
  g.contacts[1] = {centre + u * half + side * 0.02, -u};
  g.contacts[2] = {centre + u * half - side * 0.02, -u};
  g.approach = approach.normalized();
  g.spread = 0.04;
  g.aperture = 2 * half + 0.02;
  return g;
}

}  // namespace fba::test
