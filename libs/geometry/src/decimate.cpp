#include "fba/geometry/decimate.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <unordered_set>

#include "fba/geometry/mesh_io.hpp"

namespace fba::geometry {
namespace {

constexpr std::int64_t kCellsPerAxis = std::int64_t{1} << 21;  // a cube's coordinates packed in 63 bits

struct TriangleHash {
  std::size_t operator()(const std::array<int, 3>& t) const {
    std::size_t h = static_cast<std::size_t>(t[0]);
    h = h * 1000003u ^ static_cast<std::size_t>(t[1]);
    return h * 1000003u ^ static_cast<std::size_t>(t[2]);
  }
};

}  // namespace

TriangleMesh cluster_vertices(const TriangleMesh& mesh, double cell) {
  if (!(cell > 0)) throw std::invalid_argument("cluster_vertices: the cell must be positive, found " + std::to_string(cell));
  const Eigen::AlignedBox3d box = mesh_bounds(mesh);
  TriangleMesh out;
  if (mesh.triangles.empty()) return out;
  if (box.sizes().maxCoeff() / cell >= static_cast<double>(kCellsPerAxis - 1))
    throw std::invalid_argument("cluster_vertices: a cell of " + std::to_string(cell) + " m needs more than 2^21 cubes along the mesh's " +
                                std::to_string(box.sizes().maxCoeff()) + " m");
  auto cube = [&](const Eigen::Vector3f& v) {
    const Eigen::Vector3d c = ((v.cast<double>() - box.min()) / cell).array().floor();
    return (static_cast<std::int64_t>(c.x()) * kCellsPerAxis + static_cast<std::int64_t>(c.y())) * kCellsPerAxis +
           static_cast<std::int64_t>(c.z());
  };
  // Each cube's new vertex, numbered in the order of the old ones (a mesh whose vertices each have
  // a cube of their own comes back as it was); the sums make its mean.
  std::vector<char> used(mesh.vertices.size(), 0);
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) used[static_cast<std::size_t>(t[k])] = 1;
  std::unordered_map<std::int64_t, int> cube_vertex;
  std::vector<int> vertex_of(mesh.vertices.size(), -1);
  std::vector<Eigen::Vector3d> sums;
  std::vector<int> counts;
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    if (!used[v]) continue;
    const auto [it, added] = cube_vertex.emplace(cube(mesh.vertices[v]), static_cast<int>(sums.size()));
    if (added) sums.emplace_back(Eigen::Vector3d::Zero()), counts.push_back(0);
    vertex_of[v] = it->second;
    sums[static_cast<std::size_t>(it->second)] += mesh.vertices[v].cast<double>();
    ++counts[static_cast<std::size_t>(it->second)];
  }
  out.vertices.reserve(sums.size());
  for (std::size_t i = 0; i < sums.size(); ++i) out.vertices.push_back((sums[i] / counts[i]).cast<float>());
  std::unordered_set<std::array<int, 3>, TriangleHash> kept;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3i c(vertex_of[static_cast<std::size_t>(t[0])], vertex_of[static_cast<std::size_t>(t[1])],
                            vertex_of[static_cast<std::size_t>(t[2])]);
    if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) continue;
    // A triangle is the same from any of its corners, in the same turn.
    std::array<int, 3> form = {c[0], c[1], c[2]};
    std::rotate(form.begin(), std::min_element(form.begin(), form.end()), form.end());
    if (kept.insert(form).second) out.triangles.push_back(c);
  }
  return out;
}

Decimated decimate(const TriangleMesh& mesh, std::size_t max_triangles) {
  if (max_triangles == 0) throw std::invalid_argument("decimate: max_triangles must be at least 1");
  if (mesh.triangles.size() <= max_triangles) return {mesh, 0};
  // About two triangles per cube the surface crosses, and a surface crosses about 1.5 cubes per
  // cube face of its area: the first estimate, too fine more often than not.
  const double extent = mesh_bounds(mesh).sizes().maxCoeff();
  double cell = std::sqrt(3 * surface_area(mesh) / static_cast<double>(max_triangles));
  cell = std::max(cell, extent / static_cast<double>(kCellsPerAxis / 2));
  if (!(cell > 0)) cell = 1;  // no extent: every vertex is in one cube
  for (;; cell *= 1.25) {
    TriangleMesh m = cluster_vertices(mesh, cell);
    if (m.triangles.size() <= max_triangles) return {std::move(m), cell};
  }
}

}  // namespace fba::geometry
