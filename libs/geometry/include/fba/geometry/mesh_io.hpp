// Loading and saving triangle meshes, and simple whole-mesh measures.
#pragma once

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "fba/types/mesh.hpp"

namespace fba::geometry {

// Thrown for a mesh file that is missing, unreadable, or holds no triangles. what() names the
// file and the reason.
class MeshLoadError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct MeshLoadResult {
  TriangleMesh mesh;
  // Problems that did not stop loading, e.g. an OBJ naming a material library that is absent.
  std::vector<std::string> warnings;
};

// The largest mesh file loaded: a larger one is refused before it is read. Reading takes several
// times the file's size in memory (assimp's OBJ reader the most), and the limit keeps that under a
// gigabyte; a mesh that large has far more triangles than rendering or physics can use, and is
// better decimated before.
inline constexpr std::uintmax_t kMaxMeshFileBytes = std::uintmax_t{128} << 20;  // 128 MiB

// Loads any format assimp reads (OBJ, STL, OFF, glTF, ...) and PLY (read here, with the header's
// counts checked against the file's size; ASCII and both binary forms). Faces are triangulated, node
// transforms applied, and vertices welded by exact position (normals and texture coordinates
// are dropped, so UV seams do not split the surface: the result is closed if the file's surface
// is). Degenerate triangles (a repeated vertex) are dropped. Throws MeshLoadError, also for a
// file larger than kMaxMeshFileBytes (naming its size and the limit).
MeshLoadResult load_mesh_with_warnings(const std::filesystem::path& path);

// As load_mesh_with_warnings, discarding the warnings.
TriangleMesh load_mesh(const std::filesystem::path& path);

// Writes a binary little-endian PLY (float x y z vertices, uchar-counted int faces) whose data does
// not start with the byte 0x0A, which assimp 5.2.5 misreads (ASCII when no vertex order avoids it).
// Throws std::runtime_error naming the file if it cannot be written.
void write_ply(const TriangleMesh& mesh, const std::filesystem::path& path);

// Axis-aligned bounds of the vertices (empty box for an empty mesh).
Eigen::AlignedBox3d mesh_bounds(const TriangleMesh& mesh);

// Signed volume by the divergence theorem: positive for a closed mesh with outward
// (counter-clockwise) triangles; meaningless for an open mesh.
double signed_volume(const TriangleMesh& mesh);

double surface_area(const TriangleMesh& mesh);

// The smallest cube centred on box's centre that contains it, with each side enlarged by
// 2 * margin * (largest side): the root voxel for carving (vision::OctreeCarver::set_bounds uses
// margin 0) and the domain for voxelisation. Throws std::invalid_argument for an empty or
// zero-size box or a negative margin.
Eigen::AlignedBox3d cube_around(const Eigen::AlignedBox3d& box, double margin = 0.0);

// Closed test shapes (outward counter-clockwise triangles), for tests and examples.
TriangleMesh make_box(const Eigen::Vector3d& min, const Eigen::Vector3d& max);
// A UV sphere with `slices` around the z axis and `stacks` from pole to pole.
TriangleMesh make_uv_sphere(const Eigen::Vector3d& centre, double radius, int slices = 64,
                            int stacks = 32);

}  // namespace fba::geometry
