// A concave test object: a U standing on the table, two walls joined by a base, open upwards and
// at both ends. Its convex hull fills the gap between the walls; the object does not.
#pragma once

#include <array>

#include <Eigen/Core>

#include "fba/types/mesh.hpp"

namespace fba::test {

struct UShape {
  double width = 0.12;   // m along x, wall to wall, outside
  double length = 0.08;  // m along y, the extrusion
  double height = 0.10;  // m, z from 0
  double wall = 0.02;    // m, each wall's thickness along x
  double base = 0.03;    // m, the base's thickness along z
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();  // x, y

  // The gap's inner faces, x (the walls' inner sides) and z (the base's top).
  double gap_half_width() const { return width / 2 - wall; }
};

// Closed, outward counter-clockwise triangles: the U's outline in the xz plane extruded along y.
inline TriangleMesh make_u_shape(const UShape& u) {
  const double x0 = u.centre.x() - u.width / 2, x1 = u.centre.x() + u.width / 2;
  const double y0 = u.centre.y() - u.length / 2, y1 = u.centre.y() + u.length / 2;
  const double t = u.wall, b = u.base, h = u.height;
  // The outline, counter-clockwise seen from -y (x right, z up).
  const std::array<Eigen::Vector2d, 8> outline = {{{x0, 0}, {x1, 0}, {x1, h}, {x1 - t, h}, {x1 - t, b}, {x0 + t, b}, {x0 + t, h}, {x0, h}}};
  // Three quadrilaterals of outline vertices (no T-junction): the right wall, the base, the left wall.
  const std::array<std::array<int, 4>, 3> quads = {{{1, 2, 3, 4}, {0, 1, 4, 5}, {0, 5, 6, 7}}};
  TriangleMesh m;
  for (double y : {y0, y1})
    for (const auto& p : outline) m.vertices.emplace_back(float(p.x()), float(y), float(p.y()));
  auto tri = [&m](int a, int b2, int c) { m.triangles.push_back({a, b2, c}); };
  for (const auto& q : quads) {
    // Seen from -y the outline runs counter-clockwise: the y0 cap faces -y in its order, the y1
    // cap +y in the other.
    tri(q[0], q[1], q[2]), tri(q[0], q[2], q[3]);
    tri(8 + q[0], 8 + q[2], 8 + q[1]), tri(8 + q[0], 8 + q[3], 8 + q[2]);
  }
  for (int i = 0; i < 8; ++i) {  // each outline edge i -> j swept along +y: outward is +y cross (j - i)
    const int j = (i + 1) % 8;
    tri(i, 8 + j, j), tri(i, 8 + i, 8 + j);
  }
  return m;
}

}  // namespace fba::test
