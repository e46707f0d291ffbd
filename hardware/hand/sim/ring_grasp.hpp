// A grasp built from a mesh for testing the hand: three contacts 120 degrees apart around a
// vertical axis, on the mesh's outer surface at one height, approached from above. On an upright
// cylinder it is the textbook good three-finger grasp.
#pragma once

#include <stdexcept>

#include "fba/types/grasp.hpp"
#include "fba/types/mesh.hpp"

namespace fba::sim_hand {

// `mesh` in world coordinates (e.g. place_on_table's result); the axis passes through the centre
// of the mesh's bounds; `height` is world z; the thumb's contact lies at `thumb_angle` (radians,
// from +x about +z), the fingers' at thumb_angle + 120 and + 240 degrees. Each contact is where a
// horizontal ray from the axis leaves the mesh for the last time; its normal is the triangle's,
// inward. The aperture is the thumb-to-fingers distance plus 2 * clearance. Throws
// std::invalid_argument if a ray misses the mesh (the height is outside it).
Grasp ring_grasp(const TriangleMesh& mesh, double height, double thumb_angle, double clearance = 0.02);

}  // namespace fba::sim_hand
