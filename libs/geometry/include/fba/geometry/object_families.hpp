// Object meshes by family, from parameters and a seed: an object set written by the project, which
// no setting of the grasp loop was chosen on (issue 31). Each family's parameters are drawn from
// documented ranges (docs/evaluating-grasps.md, "Objects nobody tuned on") by the object's own
// seed, which the set's seed, the family's name and the object's number give: an object is the same
// whichever other families or how many objects are generated beside it, on any machine.
//
// Every mesh is one closed surface in metres, z up, centred on its bounding box: each edge shared by
// exactly two triangles that run it in opposite directions (outward, counter-clockwise seen from
// outside), positive volume, no two vertices at the same position (so that a reader welding
// vertices by position, as load_mesh does, reads the same surface back). Each is built as one
// polyhedral solid, not as a union of parts: a tool's handle is a tube that starts at a circular
// opening of the head's face, whose face is triangulated around it; a hole's wall joins the caps'
// inner loops. A union voxelised and re-extracted (marching cubes) would be closed too, but it bevels
// every edge and ripples every flat face at the voxel's scale, and the evaluation measures a grasp's
// contact normals on this surface: here a flat face is flat and an edge sharp, with a few thousand
// triangles.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "fba/types/mesh.hpp"

namespace fba::geometry {

// How far any point of a generated object is from its centre (the centre of its bounding box), at
// most: whatever way it rests and turns, it then stays within a sphere of this radius. The
// workspace of tasks/grasp.yaml is a 26 cm cube on the table (half-width 0.13 m); a batch draws the
// object's place within 2.5 cm of its centre along x and y (up to 0.0354 m off it), and 1 cm is
// left as a margin: 0.13 - 0.0354 - 0.01 = 0.0846. An object is at most 17 cm across, and so at most
// 17 cm tall (the workspace's top is 24 cm above the table).
inline constexpr double kMaxObjectRadius = 0.0845;

enum class ObjectFamily { box, cylinder, sphere, ellipsoid, superquadric, ring, l_shape, t_shape, tool, holed };

// The families in the order above, and their names ("box", "cylinder", "sphere", "ellipsoid",
// "superquadric", "ring", "l_shape", "t_shape", "tool", "holed").
const std::vector<ObjectFamily>& all_families();
std::string_view family_name(ObjectFamily family);
std::optional<ObjectFamily> family_from_name(std::string_view name);

// A convex part of an object for a physics engine, in the object's frame: a box, a cylinder or an
// ellipsoid (the engine's own shapes, whose contact with a plane it takes from the shape: MuJoCo 2.2
// gives a box lying flat its four corners, a cylinder three points around its rim), or the convex
// hull of `points`. An object's parts are the shapes it is made of (an L's two bars, a tool's head
// and handle) or, for an object that is no union of such shapes (a superquadric, a ring, a box with
// a hole), its convex hull: all that a lone object on a plane can touch it with. MuJoCo takes a
// mesh's contact with a plane at three of its points: a T's hull lying flat has six corners, and on
// the three taken it rocked and crept across the table for a minute; as two boxes it rests.
struct ConvexPart {
  enum class Kind { box, cylinder, ellipsoid, hull };
  Kind kind = Kind::hull;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  // the part's x, y, z (columns) in the object's frame
  // Box: half sizes; cylinder: radius, radius, half its height (along its z); ellipsoid: semi-axes.
  Eigen::Vector3d half = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3f> points;  // hull: the points whose hull it is
};

struct FamilyObject {
  ObjectFamily family = ObjectFamily::box;
  int index = 0;               // its number in its family, from 0
  std::string name;            // "box-03"
  std::string kind;            // the family's variety: e.g. "plate" or "block", "round hole" or "square hole"
  std::uint64_t seed = 0;      // the object's own seed (object_seed)
  // The drawn parameters in the order drawn, as the mesh was made from them: metres, except the
  // superquadric's exponents; lengths rounded to 0.1 mm, exponents to 0.01.
  std::vector<std::pair<std::string, double>> parameters;
  TriangleMesh mesh;           // centred on its bounding box, within kMaxObjectRadius of the centre
  std::vector<ConvexPart> parts;  // in the mesh's frame
};

// The object's seed: splitmix64 over the set's seed, an FNV-1a hash of the family's name and the
// index, so that it does not change with the families or the counts generated beside it.
std::uint64_t object_seed(std::uint64_t set_seed, ObjectFamily family, int index);

// Object `index` of `family` in the set of `set_seed`. Parameters are drawn within the family's
// ranges (see the .cpp and docs/evaluating-grasps.md) and drawn again while the object would reach
// beyond kMaxObjectRadius. Throws std::invalid_argument for a negative index.
FamilyObject make_family_object(ObjectFamily family, std::uint64_t set_seed, int index);

// The shapes, from their parameters (metres), each closed and outward, in its own frame as
// described; make_family_object centres them. Each throws std::invalid_argument for parameters
// that give no solid (a size not positive, a hole wider than its box, ...), naming them.
//
// A box [-sx/2, sx/2] x [-sy/2, sy/2] x [-sz/2, sz/2].
TriangleMesh make_box_shape(double sx, double sy, double sz);
// A cylinder about z, its base at z = -height/2, as a prism on a polygon of `segments` sides.
TriangleMesh make_cylinder_shape(double radius, double height, int segments = 64);
// A superellipsoid |x/a|^(2/e2) + |y/b|^(2/e2))^(e2/e1) + |z/c|^(2/e1) = 1 (e1 north-south, e2
// east-west; 1, 1: an ellipsoid; towards 0 a box; 2 an octahedron; convex for e1, e2 in (0, 2]),
// sampled on a cube's faces (n x n each) projected along the rays from its centre onto the surface,
// which is star-shaped: no poles, no degenerate triangles.
TriangleMesh make_superquadric_shape(const Eigen::Vector3d& semi_axes, double e1, double e2, int n = 16);
// A ring about z: a tube of elliptic cross-section (half-widths `tube_radial` across the ring,
// `tube_vertical` along z) around a circle of radius `major` (> tube_radial).
TriangleMesh make_ring_shape(double major, double tube_radial, double tube_vertical, int major_segments = 64,
                             int minor_segments = 24);
// A prism of thickness along z on the L of two bars, [0, length_x] x [0, width_x] and
// [0, width_y] x [0, length_y].
TriangleMesh make_l_shape(double length_x, double width_x, double length_y, double width_y, double thickness);
// A prism on a T: the bar [-bar_length/2, bar_length/2] x [0, bar_width] and the stem
// [-stem_width/2, stem_width/2] x [-stem_length, 0].
TriangleMesh make_t_shape(double bar_length, double bar_width, double stem_length, double stem_width, double thickness);
// A tool: a cylindrical handle (radius, length) along x joined to the middle of a box head's -x face;
// the head spans [0, head_x] along x, head_y across, head_z tall, the handle [-handle_length, 0].
TriangleMesh make_tool_shape(double handle_radius, double handle_length, double head_x, double head_y, double head_z,
                             int segments = 48);
// A box sx x sy x sz with a hole through it along z, round (radius) or square (half-side
// `hole_size`), centred at (hole_x, hole_y) off the box's centre.
TriangleMesh make_holed_box_shape(double sx, double sy, double sz, bool round, double hole_size, double hole_x = 0,
                                  double hole_y = 0, int segments = 64);

// The solid's mass properties per unit density, by the divergence theorem over the closed,
// outward mesh: volume (m^3), centre of mass, and the inertia tensor about the centre of mass
// divided by the mass (m^2).
struct SolidProperties {
  double volume = 0;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
};
SolidProperties solid_properties(const TriangleMesh& mesh);

}  // namespace fba::geometry
