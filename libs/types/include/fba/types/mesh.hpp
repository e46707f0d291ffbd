// A triangle mesh: object models for simulation and evaluation, and carved models for display.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "fba/data_type.hpp"

namespace fba {

struct TriangleMesh {
  std::vector<Eigen::Vector3f> vertices;   // metres, world coordinates
  std::vector<Eigen::Vector3i> triangles;  // indices into vertices, counter-clockwise outward
};

}  // namespace fba

FBA_DATA_TYPE(fba::TriangleMesh, "fba.TriangleMesh", "A triangle mesh in world coordinates (metres).");
