#include "fba/geometry/mesh_io.hpp"

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <numbers>
#include <sstream>
#include <unordered_map>

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

namespace fba::geometry {
namespace {

std::string describe(const std::filesystem::path& path) { return "mesh '" + path.string() + "'"; }

// assimp's OBJ reader only logs a missing material library (to a global logger we do not want
// to own), so look for it ourselves and report it as a warning the caller can show.
void check_obj_material_libraries(const std::filesystem::path& path,
                                  std::vector<std::string>& warnings) {
  std::string ext = path.extension().string();
  for (auto& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext != ".obj") return;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("mtllib", 0) != 0) continue;
    std::istringstream fields(line.substr(6));
    std::string name;
    while (fields >> name) {
      if (!std::filesystem::exists(path.parent_path() / name))
        warnings.push_back(describe(path) + ": material library '" + name +
                           "' not found; loaded without materials");
    }
  }
}

struct PositionHash {
  std::size_t operator()(const Eigen::Vector3f& p) const {
    std::uint32_t bits[3];
    std::memcpy(bits, p.data(), sizeof bits);
    std::size_t h = bits[0];
    h = h * 1000003u ^ bits[1];
    h = h * 1000003u ^ bits[2];
    return h;
  }
};
struct PositionEqual {
  // Exact comparison on purpose: welding only joins copies of the same vertex, never near ones.
  bool operator()(const Eigen::Vector3f& a, const Eigen::Vector3f& b) const { return a == b; }
};

}  // namespace

MeshLoadResult load_mesh_with_warnings(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    throw MeshLoadError("cannot load " + describe(path) + ": file does not exist");
  if (!std::filesystem::is_regular_file(path, ec))
    throw MeshLoadError("cannot load " + describe(path) + ": not a regular file");
  {
    std::ifstream probe(path, std::ios::binary);
    if (!probe) throw MeshLoadError("cannot load " + describe(path) + ": file cannot be opened");
  }

  MeshLoadResult result;
  check_obj_material_libraries(path, result.warnings);

  Assimp::Importer importer;
  // Drop everything but positions before joining, so vertices split only by normals or texture
  // coordinates (UV seams) become one again and the surface stays closed.
  importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS,
                              aiComponent_NORMALS | aiComponent_TANGENTS_AND_BITANGENTS |
                                  aiComponent_COLORS | aiComponent_TEXCOORDS |
                                  aiComponent_BONEWEIGHTS | aiComponent_ANIMATIONS |
                                  aiComponent_TEXTURES | aiComponent_LIGHTS |
                                  aiComponent_CAMERAS | aiComponent_MATERIALS);
  const unsigned flags = aiProcess_RemoveComponent | aiProcess_Triangulate |
                         aiProcess_JoinIdenticalVertices | aiProcess_PreTransformVertices |
                         aiProcess_SortByPType;
  const aiScene* scene = importer.ReadFile(path.string(), flags);
  if (!scene) {
    throw MeshLoadError("cannot load " + describe(path) + ": " +
                        std::string(importer.GetErrorString()));
  }

  // Weld across assimp meshes (an OBJ with several objects or materials gives several).
  std::unordered_map<Eigen::Vector3f, int, PositionHash, PositionEqual> index_of;
  TriangleMesh& mesh = result.mesh;
  std::size_t skipped_degenerate = 0;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* am = scene->mMeshes[m];
    std::vector<int> remap(am->mNumVertices);
    for (unsigned v = 0; v < am->mNumVertices; ++v) {
      const aiVector3D& p = am->mVertices[v];
      Eigen::Vector3f q(p.x, p.y, p.z);
      if (!q.allFinite())
        throw MeshLoadError("cannot load " + describe(path) + ": non-finite vertex coordinate");
      auto [it, inserted] = index_of.emplace(q, static_cast<int>(mesh.vertices.size()));
      if (inserted) mesh.vertices.push_back(q);
      remap[v] = it->second;
    }
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
      const aiFace& face = am->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines carry no surface
      Eigen::Vector3i t(remap[face.mIndices[0]], remap[face.mIndices[1]], remap[face.mIndices[2]]);
      if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
        ++skipped_degenerate;
        continue;
      }
      mesh.triangles.push_back(t);
    }
  }
  if (mesh.triangles.empty())
    throw MeshLoadError("cannot load " + describe(path) + ": the file holds no triangles");
  if (skipped_degenerate > 0)
    result.warnings.push_back(describe(path) + ": dropped " + std::to_string(skipped_degenerate) +
                              " degenerate triangles");
  // Unreferenced vertices are harmless for rendering and voxelisation; keep indices stable.
  return result;
}

TriangleMesh load_mesh(const std::filesystem::path& path) {
  return load_mesh_with_warnings(path).mesh;
}

void write_ply(const TriangleMesh& mesh, const std::filesystem::path& path) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw std::runtime_error("cannot write PLY '" + path.string() + "'");
  out << "ply\nformat binary_little_endian 1.0\ncomment written by fba_geometry\n"
      << "element vertex " << mesh.vertices.size() << "\n"
      << "property float x\nproperty float y\nproperty float z\n"
      << "element face " << mesh.triangles.size() << "\n"
      << "property list uchar int vertex_indices\nend_header\n";
  static_assert(std::endian::native == std::endian::little, "PLY writer assumes little endian");
  for (const auto& v : mesh.vertices) out.write(reinterpret_cast<const char*>(v.data()), 12);
  for (const auto& t : mesh.triangles) {
    const unsigned char three = 3;
    out.write(reinterpret_cast<const char*>(&three), 1);
    out.write(reinterpret_cast<const char*>(t.data()), 12);
  }
  if (!out) throw std::runtime_error("error while writing PLY '" + path.string() + "'");
}

Eigen::AlignedBox3d mesh_bounds(const TriangleMesh& mesh) {
  Eigen::AlignedBox3d box;  // default-constructed: empty
  for (const auto& v : mesh.vertices) box.extend(v.cast<double>());
  return box;
}

double signed_volume(const TriangleMesh& mesh) {
  double six_v = 0;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices[t[0]].cast<double>();
    const Eigen::Vector3d b = mesh.vertices[t[1]].cast<double>();
    const Eigen::Vector3d c = mesh.vertices[t[2]].cast<double>();
    six_v += a.dot(b.cross(c));
  }
  return six_v / 6.0;
}

double surface_area(const TriangleMesh& mesh) {
  double twice = 0;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices[t[0]].cast<double>();
    const Eigen::Vector3d b = mesh.vertices[t[1]].cast<double>();
    const Eigen::Vector3d c = mesh.vertices[t[2]].cast<double>();
    twice += (b - a).cross(c - a).norm();
  }
  return twice / 2.0;
}

Eigen::AlignedBox3d cube_around(const Eigen::AlignedBox3d& box, double margin) {
  if (box.isEmpty()) throw std::invalid_argument("cube_around: empty box");
  if (!(margin >= 0)) throw std::invalid_argument("cube_around: negative margin");
  const double side = box.sizes().maxCoeff() * (1.0 + 2.0 * margin);
  if (!(side > 0)) throw std::invalid_argument("cube_around: the box has zero size");
  const Eigen::Vector3d half = Eigen::Vector3d::Constant(side / 2.0);
  return Eigen::AlignedBox3d(box.center() - half, box.center() + half);
}

TriangleMesh make_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  TriangleMesh m;
  for (int i = 0; i < 8; ++i)
    m.vertices.emplace_back(Eigen::Vector3d((i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(),
                                            (i & 4) ? hi.z() : lo.z())
                                .cast<float>());
  // Two counter-clockwise (seen from outside) triangles per face.
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    m.triangles.emplace_back(q[0], q[1], q[2]);
    m.triangles.emplace_back(q[0], q[2], q[3]);
  }
  return m;
}

TriangleMesh make_uv_sphere(const Eigen::Vector3d& centre, double radius, int slices, int stacks) {
  TriangleMesh m;
  m.vertices.emplace_back((centre + Eigen::Vector3d(0, 0, radius)).cast<float>());  // north pole
  for (int s = 1; s < stacks; ++s) {
    const double theta = std::numbers::pi * s / stacks;
    for (int a = 0; a < slices; ++a) {
      const double phi = 2 * std::numbers::pi * a / slices;
      m.vertices.emplace_back(
          (centre + radius * Eigen::Vector3d(std::sin(theta) * std::cos(phi),
                                             std::sin(theta) * std::sin(phi), std::cos(theta)))
              .cast<float>());
    }
  }
  m.vertices.emplace_back((centre - Eigen::Vector3d(0, 0, radius)).cast<float>());  // south pole
  const int south = static_cast<int>(m.vertices.size()) - 1;
  auto ring = [&](int s, int a) { return 1 + (s - 1) * slices + (a % slices); };
  for (int a = 0; a < slices; ++a) m.triangles.emplace_back(0, ring(1, a), ring(1, a + 1));
  for (int s = 1; s < stacks - 1; ++s)
    for (int a = 0; a < slices; ++a) {
      m.triangles.emplace_back(ring(s, a), ring(s + 1, a), ring(s + 1, a + 1));
      m.triangles.emplace_back(ring(s, a), ring(s + 1, a + 1), ring(s, a + 1));
    }
  for (int a = 0; a < slices; ++a)
    m.triangles.emplace_back(south, ring(stacks - 1, a + 1), ring(stacks - 1, a));
  return m;
}

}  // namespace fba::geometry
