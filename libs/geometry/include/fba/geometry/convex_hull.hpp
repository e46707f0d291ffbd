// A mesh's convex hull, and whether the mesh is convex: a convex solid is its own exact convex
// decomposition, one piece a physics engine collides smoothly (box_decomposition.hpp's boxes are a
// staircase on a curved surface).
#pragma once

#include <stdexcept>
#include <vector>

#include <Eigen/Core>

#include "fba/types/mesh.hpp"

namespace fba::geometry {

class ConvexHullError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ConvexHull {
  std::vector<Eigen::Vector3d> vertices;  // the hull's vertices, the mesh's coordinates
  double volume = 0;                      // m^3
};

// The convex hull of the mesh's vertices (qhull). Throws ConvexHullError when they span no volume
// (fewer than four points, or all in a plane).
ConvexHull convex_hull(const TriangleMesh& mesh);

// The convex hull of points in a plane (Andrew's monotone chain): its corners counter-clockwise from
// the lowest x (then y), collinear points left out; fewer than three distinct points come back as
// they are, sorted.
std::vector<Eigen::Vector2d> convex_hull_2d(std::vector<Eigen::Vector2d> points);

// A closed mesh whose volume is at least this share of its hull's is taken as convex: a convex
// mesh is exactly its hull, whatever its tessellation; the rest allows for rounding in the file.
inline constexpr double kConvexVolumeShare = 0.99;

}  // namespace fba::geometry
