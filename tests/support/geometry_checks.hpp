// Helpers shared by the geometry library's tests and fba-evaluate's: the YCB meshes, a temporary folder,
// and whether a mesh is a closed, consistently oriented surface.
#pragma once

#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <tuple>

#include <Eigen/Geometry>

#include "fba/types/mesh.hpp"

#include "support/temp_dir.hpp"
#include "support/build_paths.hpp"

namespace fba::geometry::test {

inline std::filesystem::path data() { return fba::test::data_dir(); }

inline std::filesystem::path ycb_mesh(const std::string& name) {
  return data() / "ycb" / name / "model.obj";
}

inline const char* const kYcbNames[] = {"YcbMustardBottle", "YcbMasterChefCan", "YcbBanana",
                                        "YcbCrackerBox"};

using fba::test::TempDir;

// What is wrong with the mesh as a closed, consistently oriented surface ("" when nothing): each
// directed edge once, and its reverse once (so each edge has two triangles, which run it in opposite
// directions); no degenerate triangle; no two vertices at one position.
inline std::string closed_surface_fault(const TriangleMesh& m) {
  std::map<std::pair<int, int>, int> directed;
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    const auto& tri = m.triangles[t];
    const Eigen::Vector3d a = m.vertices[tri[0]].cast<double>(), b = m.vertices[tri[1]].cast<double>(), c = m.vertices[tri[2]].cast<double>();
    if (!((b - a).cross(c - a).norm() / 2 > 1e-10)) return "triangle " + std::to_string(t) + " is degenerate";
    for (int k = 0; k < 3; ++k)
      if (++directed[{tri[k], tri[(k + 1) % 3]}] > 1)
        return "edge " + std::to_string(tri[k]) + "-" + std::to_string(tri[(k + 1) % 3]) + " runs the same way in two triangles";
  }
  for (const auto& [e, n] : directed)
    if (!directed.count({e.second, e.first})) return "edge " + std::to_string(e.first) + "-" + std::to_string(e.second) + " has one triangle";
  std::set<std::tuple<float, float, float>> at;
  for (const auto& v : m.vertices)
    if (!at.emplace(v.x(), v.y(), v.z()).second) return "two vertices at one position";
  return "";
}

}  // namespace fba::geometry::test
