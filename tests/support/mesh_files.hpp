// Meshes written for a test into its temporary folder, in the formats users give (the project's
// own writer makes PLY only).
#pragma once

#include <charconv>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <string_view>

#include "fba/types/mesh.hpp"

namespace fba::test {

// A Wavefront OBJ: each vertex as the shortest text that reads back as the same float, faces
// numbered from 1.
inline void write_obj(const TriangleMesh& mesh, const std::filesystem::path& path) {
  std::ofstream out(path);
  char buf[32];
  for (const auto& v : mesh.vertices) {
    out << 'v';
    for (int k = 0; k < 3; ++k) out << ' ' << std::string_view(buf, std::to_chars(buf, buf + sizeof buf, v[k]).ptr);
    out << '\n';
  }
  for (const auto& t : mesh.triangles) out << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
  if (!out) throw std::runtime_error("cannot write the test mesh " + path.string());
}

}  // namespace fba::test
