// Fewer triangles for the same shape: meshes finer than rendering or physics needs.
#pragma once

#include <cstddef>

#include "fba/types/mesh.hpp"

namespace fba::geometry {

// Vertex clustering: the vertices in each cube of a grid of edge `cell` (from the mesh's lowest
// corner) become one, at their mean; a triangle with two corners in one cube vanishes, and a
// triangle repeated is kept once. No vertex moves farther than a cube's diagonal, so neither does
// the surface nor its convex hull; parts thinner than a cube may become non-manifold. Only the
// vertices of triangles are kept. Throws std::invalid_argument for a cell that is not positive or
// so small that the grid would need more than 2^21 cubes along an axis.
TriangleMesh cluster_vertices(const TriangleMesh& mesh, double cell);

struct Decimated {
  TriangleMesh mesh;
  double cell = 0;  // the grid's cube edge, metres; 0 when the mesh was within the bound as it was
};

// The mesh as it is if it has at most max_triangles, else clustered on the finest grid, coarsened
// step by step from one estimated from its area, that brings it within the bound. Throws
// std::invalid_argument for a max_triangles of 0.
Decimated decimate(const TriangleMesh& mesh, std::size_t max_triangles);

}  // namespace fba::geometry
