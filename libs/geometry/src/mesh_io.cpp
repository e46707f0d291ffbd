#include "fba/geometry/mesh_io.hpp"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <numbers>
#include <sstream>
#include <unordered_map>

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

namespace fba::geometry {
namespace {

std::string describe(const std::filesystem::path& path) { return "mesh '" + path.string() + "'"; }

std::string mebibytes(std::uintmax_t bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f MiB", static_cast<double>(bytes) / (1 << 20));
  return text;
}

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
    // -0 and 0 are equal positions, so they must hash alike: adding 0 makes -0 into 0.
    const Eigen::Vector3f q = p.array() + 0.0f;
    std::uint32_t bits[3];
    std::memcpy(bits, q.data(), sizeof bits);
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


// Adds faces (polygons, fan-triangulated) over `positions` to `mesh`, welding vertices by exact
// position across calls; counts the degenerate triangles dropped.
class MeshBuilder {
 public:
  MeshBuilder(const std::filesystem::path& path, TriangleMesh& mesh) : path_(path), mesh_(mesh) {}

  std::vector<int> add_vertices(const std::vector<Eigen::Vector3f>& positions) {
    std::vector<int> remap(positions.size());
    for (std::size_t v = 0; v < positions.size(); ++v) {
      const Eigen::Vector3f& q = positions[v];
      if (!q.allFinite())
        throw MeshLoadError("cannot load " + describe(path_) + ": non-finite coordinate in vertex " + std::to_string(v));
      auto [it, inserted] = index_of_.emplace(q, static_cast<int>(mesh_.vertices.size()));
      if (inserted) mesh_.vertices.push_back(q);
      remap[v] = it->second;
    }
    return remap;
  }

  void add_triangle(int a, int b, int c) {
    if (a == b || b == c || a == c) {
      ++skipped_degenerate;
      return;
    }
    mesh_.triangles.emplace_back(a, b, c);
  }

  std::size_t skipped_degenerate = 0;

 private:
  const std::filesystem::path& path_;
  TriangleMesh& mesh_;
  std::unordered_map<Eigen::Vector3f, int, PositionHash, PositionEqual> index_of_;
};

// PLY is read here rather than by assimp: assimp 5.2.5 drops a binary file's first data byte
// when it is 0x0A (taking it for the end of the header line) and then reads past its buffers.
// Every count in the header is checked against the file's size before anything is allocated,
// so a truncated or lying file is an error naming what was expected and what was found.
class PlyReader {
 public:
  PlyReader(const std::filesystem::path& path, std::string bytes) : path_(path), bytes_(std::move(bytes)) {}

  void read(MeshBuilder& out) {
    parse_header();
    check_size();
    if (format_ == Format::Ascii) read_body<true>(out);
    else read_body<false>(out);
  }

 private:
  enum class Format { Ascii, BinaryLittle, BinaryBig };
  enum class Scalar { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };
  struct Property {
    std::string name;
    Scalar type = Scalar::Float32;
    bool list = false;
    Scalar count_type = Scalar::UInt8;
  };
  struct Element {
    std::string name;
    std::uint64_t count = 0;
    int line = 0;
    std::vector<Property> properties;
  };

  [[noreturn]] void fail(const std::string& what) const {
    throw MeshLoadError("cannot load " + describe(path_) + ": " + what);
  }
  [[noreturn]] void fail_at_line(int line, const std::string& what) const {
    throw MeshLoadError("cannot load " + describe(path_) + ": line " + std::to_string(line) + ": " + what);
  }

  static std::size_t size_of(Scalar s) {
    switch (s) {
      case Scalar::Int8: case Scalar::UInt8: return 1;
      case Scalar::Int16: case Scalar::UInt16: return 2;
      case Scalar::Int32: case Scalar::UInt32: case Scalar::Float32: return 4;
      case Scalar::Float64: return 8;
    }
    return 0;
  }

  Scalar scalar(const std::string& name, int line) const {
    static const std::pair<const char*, Scalar> names[] = {
        {"char", Scalar::Int8},     {"int8", Scalar::Int8},       {"uchar", Scalar::UInt8},     {"uint8", Scalar::UInt8},
        {"short", Scalar::Int16},   {"int16", Scalar::Int16},     {"ushort", Scalar::UInt16},   {"uint16", Scalar::UInt16},
        {"int", Scalar::Int32},     {"int32", Scalar::Int32},     {"uint", Scalar::UInt32},     {"uint32", Scalar::UInt32},
        {"float", Scalar::Float32}, {"float32", Scalar::Float32}, {"double", Scalar::Float64}, {"float64", Scalar::Float64}};
    for (const auto& [n, s] : names)
      if (name == n) return s;
    fail_at_line(line, "expected a PLY scalar type (char, uchar, short, ushort, int, uint, float, double), found '" + name + "'");
  }

  // The header, line by line up to "end_header" and its single line end.
  void parse_header() {
    int line_no = 0;
    bool have_format = false;
    for (;;) {
      if (pos_ >= bytes_.size()) fail("expected 'end_header' to close the PLY header, found the end of the file");
      const std::size_t eol = bytes_.find('\n', pos_);
      if (eol == std::string::npos) fail("expected 'end_header' to close the PLY header, found the end of the file");
      std::string line = bytes_.substr(pos_, eol - pos_);
      if (!line.empty() && line.back() == '\r') line.pop_back();
      pos_ = eol + 1;
      ++line_no;
      std::istringstream fields(line);
      std::vector<std::string> w;
      for (std::string t; fields >> t;) w.push_back(t);
      if (line_no == 1) {
        if (line != "ply") fail("expected 'ply' on the first line of a PLY file, found something else");
        continue;
      }
      if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
      if (w[0] == "end_header") break;
      if (w[0] == "format") {
        if (w.size() != 3 || w[2] != "1.0") fail_at_line(line_no, "expected 'format <ascii|binary_little_endian|binary_big_endian> 1.0'");
        if (w[1] == "ascii") format_ = Format::Ascii;
        else if (w[1] == "binary_little_endian") format_ = Format::BinaryLittle;
        else if (w[1] == "binary_big_endian") format_ = Format::BinaryBig;
        else fail_at_line(line_no, "expected the format ascii, binary_little_endian or binary_big_endian, found '" + w[1] + "'");
        have_format = true;
      } else if (w[0] == "element") {
        std::uint64_t count = 0;
        if (w.size() != 3 || std::from_chars(w[2].data(), w[2].data() + w[2].size(), count).ptr != w[2].data() + w[2].size())
          fail_at_line(line_no, "expected 'element <name> <count>' with a whole count, found '" + line + "'");
        elements_.push_back({w[1], count, line_no, {}});
      } else if (w[0] == "property") {
        if (elements_.empty()) fail_at_line(line_no, "expected an 'element' line before its properties");
        Property p;
        if (w.size() == 5 && w[1] == "list") {
          p.list = true;
          p.count_type = scalar(w[2], line_no);
          if (p.count_type == Scalar::Float32 || p.count_type == Scalar::Float64)
            fail_at_line(line_no, "expected an integer type for a list's count, found '" + w[2] + "'");
          p.type = scalar(w[3], line_no);
          p.name = w[4];
        } else if (w.size() == 3) {
          p.type = scalar(w[1], line_no);
          p.name = w[2];
        } else {
          fail_at_line(line_no, "expected 'property <type> <name>' or 'property list <count type> <type> <name>', found '" + line + "'");
        }
        elements_.back().properties.push_back(p);
      } else {
        fail_at_line(line_no, "expected a PLY header line (format, element, property, comment, end_header), found '" + line + "'");
      }
    }
    if (!have_format) fail("expected a 'format' line in the PLY header, found none");
    header_lines_ = line_no;
  }

  // The least number of bytes the body can take (every list empty; in ASCII, one digit and one
  // separator per value): more elements than the file can hold are refused before any allocation.
  void check_size() const {
    const std::uint64_t body = bytes_.size() - pos_ + (format_ == Format::Ascii ? 1 : 0);  // a last value needs no separator
    std::uint64_t least = 0;
    for (const Element& e : elements_) {
      std::uint64_t per = 0;
      for (const Property& p : e.properties)
        per += format_ == Format::Ascii ? 2 : p.list ? size_of(p.count_type) : size_of(p.type);
      if (per > 0 && e.count > body / per)
        fail("the header declares " + std::to_string(e.count) + " '" + e.name + "' elements of at least " + std::to_string(per) +
             " bytes each, but the data after the header is " + std::to_string(bytes_.size() - pos_) + " bytes");
      least += per * e.count;
      if (least > body)
        fail("the header's elements need at least " + std::to_string(least) + " bytes, but the data after the header is " +
             std::to_string(bytes_.size() - pos_) + " bytes");
    }
  }

  // One scalar of the body, as a double (exact for every PLY integer type).
  template <bool Ascii>
  double value(Scalar s, const Element& e, std::uint64_t i) {
    if constexpr (Ascii) {
      while (pos_ < bytes_.size() && std::isspace(static_cast<unsigned char>(bytes_[pos_]))) {
        if (bytes_[pos_] == '\n') ++line_;
        ++pos_;
      }
      if (pos_ >= bytes_.size())
        fail("expected " + std::to_string(e.count) + " '" + e.name + "' elements, found the end of the file in element " + std::to_string(i));
      const std::size_t end = std::min(bytes_.find_first_of(" \t\r\n", pos_), bytes_.size());
      double v = 0;
      const auto r = std::from_chars(bytes_.data() + pos_, bytes_.data() + end, v);
      if (r.ec != std::errc() || r.ptr != bytes_.data() + end)
        fail_at_line(line_, "expected a number in '" + e.name + "' element " + std::to_string(i) + ", found '" +
                                bytes_.substr(pos_, std::min<std::size_t>(end - pos_, 32)) + "'");
      pos_ = end;
      if ((s != Scalar::Float32 && s != Scalar::Float64) && v != std::floor(v))
        fail_at_line(line_, "expected a whole number in '" + e.name + "' element " + std::to_string(i) + ", found " + std::to_string(v));
      return v;
    } else {
      const std::size_t n = size_of(s);
      if (bytes_.size() - pos_ < n)
        fail("expected " + std::to_string(e.count) + " '" + e.name + "' elements, found the end of the file in element " + std::to_string(i));
      unsigned char b[8];
      std::memcpy(b, bytes_.data() + pos_, n);
      pos_ += n;
      if ((format_ == Format::BinaryBig) != (std::endian::native == std::endian::big)) std::reverse(b, b + n);
      switch (s) {
        case Scalar::Int8: { std::int8_t x; std::memcpy(&x, b, 1); return x; }
        case Scalar::UInt8: return b[0];
        case Scalar::Int16: { std::int16_t x; std::memcpy(&x, b, 2); return x; }
        case Scalar::UInt16: { std::uint16_t x; std::memcpy(&x, b, 2); return x; }
        case Scalar::Int32: { std::int32_t x; std::memcpy(&x, b, 4); return x; }
        case Scalar::UInt32: { std::uint32_t x; std::memcpy(&x, b, 4); return x; }
        case Scalar::Float32: { float x; std::memcpy(&x, b, 4); return x; }
        case Scalar::Float64: { double x; std::memcpy(&x, b, 8); return x; }
      }
      return 0;
    }
  }

  template <bool Ascii>
  void read_body(MeshBuilder& out) {
    line_ = header_lines_ + 1;
    const Element* vertex_element = nullptr;
    std::vector<Eigen::Vector3f> positions;
    std::vector<int> remap;
    std::vector<int> polygon;
    for (const Element& e : elements_) {
      if (e.name == "vertex") {
        if (vertex_element) fail_at_line(e.line, "expected one 'vertex' element, found a second");
        vertex_element = &e;
        int xyz[3] = {-1, -1, -1};
        for (std::size_t k = 0; k < e.properties.size(); ++k)
          for (int a = 0; a < 3; ++a)
            if (e.properties[k].name == std::string(1, char('x' + a))) {
              if (e.properties[k].list) fail_at_line(e.line, "expected vertex property '" + e.properties[k].name + "' to be a scalar, found a list");
              xyz[a] = static_cast<int>(k);
            }
        if (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0) fail_at_line(e.line, "expected vertex properties x, y and z, found fewer");
        positions.resize(static_cast<std::size_t>(e.count));
        for (std::uint64_t i = 0; i < e.count; ++i)
          for (std::size_t k = 0; k < e.properties.size(); ++k) {
            const double v = skip_or_read<Ascii>(e.properties[k], e, i);
            for (int a = 0; a < 3; ++a)
              if (xyz[a] == static_cast<int>(k)) positions[i][a] = static_cast<float>(v);
          }
        remap = out.add_vertices(positions);
      } else if (e.name == "face") {
        if (!vertex_element) fail_at_line(e.line, "expected the 'vertex' element before 'face'");
        int indices = -1;
        for (std::size_t k = 0; k < e.properties.size(); ++k)
          if (e.properties[k].list && (e.properties[k].name == "vertex_indices" || e.properties[k].name == "vertex_index"))
            indices = static_cast<int>(k);
        if (indices < 0) fail_at_line(e.line, "expected a list property 'vertex_indices' in element 'face', found none");
        for (std::uint64_t i = 0; i < e.count; ++i)
          for (std::size_t k = 0; k < e.properties.size(); ++k) {
            const Property& p = e.properties[k];
            if (static_cast<int>(k) != indices) {
              skip_or_read<Ascii>(p, e, i);
              continue;
            }
            const double n = value<Ascii>(p.count_type, e, i);
            if (n < 0) fail("expected a list length in face " + std::to_string(i) + ", found " + std::to_string(n));
            polygon.clear();
            for (double j = 0; j < n; ++j) {
              const double v = value<Ascii>(p.type, e, i);
              if (!(v >= 0 && v < static_cast<double>(remap.size())))
                fail("face " + std::to_string(i) + " names vertex " + std::to_string(static_cast<long long>(v)) + ", but there are " +
                     std::to_string(remap.size()) + " vertices");
              polygon.push_back(remap[static_cast<std::size_t>(v)]);
            }
            // Points and lines carry no surface; a polygon becomes a fan of triangles.
            for (std::size_t j = 2; j < polygon.size(); ++j) out.add_triangle(polygon[0], polygon[j - 1], polygon[j]);
          }
      } else {
        for (std::uint64_t i = 0; i < e.count; ++i)
          for (const Property& p : e.properties) skip_or_read<Ascii>(p, e, i);
      }
    }
    if constexpr (!Ascii) {
      if (pos_ != bytes_.size())
        fail("expected the data to end after the header's elements, found " + std::to_string(bytes_.size() - pos_) + " more bytes");
    }
  }

  // Reads a scalar property (its value), or passes over a list property (returns 0).
  template <bool Ascii>
  double skip_or_read(const Property& p, const Element& e, std::uint64_t i) {
    if (!p.list) return value<Ascii>(p.type, e, i);
    const double n = value<Ascii>(p.count_type, e, i);
    if (n < 0) fail("expected a list length in '" + e.name + "' element " + std::to_string(i) + ", found " + std::to_string(n));
    for (double j = 0; j < n; ++j) value<Ascii>(p.type, e, i);
    return 0;
  }

  const std::filesystem::path& path_;
  std::string bytes_;
  std::size_t pos_ = 0;
  Format format_ = Format::Ascii;
  std::vector<Element> elements_;
  int header_lines_ = 0;
  int line_ = 0;  // ASCII: the line being read
};

bool is_ply(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  for (auto& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".ply") return true;
  std::ifstream in(path, std::ios::binary);
  char magic[4] = {};
  in.read(magic, 4);
  return in.gcount() == 4 && std::memcmp(magic, "ply", 3) == 0 && (magic[3] == '\n' || magic[3] == '\r');
}

MeshLoadResult finish(const std::filesystem::path& path, MeshLoadResult result, std::size_t skipped_degenerate) {
  if (result.mesh.triangles.empty())
    throw MeshLoadError("cannot load " + describe(path) + ": the file holds no triangles");
  if (skipped_degenerate > 0)
    result.warnings.push_back(describe(path) + ": dropped " + std::to_string(skipped_degenerate) + " degenerate triangles");
  // Unreferenced vertices are harmless for rendering and voxelisation; keep indices stable.
  return result;
}

}  // namespace

MeshLoadResult load_mesh_with_warnings(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    throw MeshLoadError("cannot load " + describe(path) + ": file does not exist");
  if (!std::filesystem::is_regular_file(path, ec))
    throw MeshLoadError("cannot load " + describe(path) + ": not a regular file");
  if (const std::uintmax_t size = std::filesystem::file_size(path, ec); !ec && size > kMaxMeshFileBytes)
    throw MeshLoadError("cannot load " + describe(path) + ": the file is " + mebibytes(size) + " (" + std::to_string(size) +
                        " bytes), more than the " + mebibytes(kMaxMeshFileBytes) +
                        " a mesh file may have (reading takes several times its size in memory); decimate it to fewer triangles");
  {
    std::ifstream probe(path, std::ios::binary);
    if (!probe) throw MeshLoadError("cannot load " + describe(path) + ": file cannot be opened");
  }

  MeshLoadResult result;
  if (is_ply(path)) {
    std::ifstream in(path, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!in.good() && !in.eof()) throw MeshLoadError("cannot load " + describe(path) + ": read error");
    MeshBuilder builder(path, result.mesh);
    PlyReader(path, std::move(bytes)).read(builder);
    return finish(path, std::move(result), builder.skipped_degenerate);
  }
  check_obj_material_libraries(path, result.warnings);

  Assimp::Importer importer;
  // Only positions are kept. Vertices are welded below by exact position, so that those split by
  // normals or texture coordinates (UV seams) become one again and the surface stays closed;
  // assimp's JoinIdenticalVertices would also join near ones, and take more memory than the
  // reading itself on a large file.
  importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS,
                              aiComponent_NORMALS | aiComponent_TANGENTS_AND_BITANGENTS |
                                  aiComponent_COLORS | aiComponent_TEXCOORDS |
                                  aiComponent_BONEWEIGHTS | aiComponent_ANIMATIONS |
                                  aiComponent_TEXTURES | aiComponent_LIGHTS |
                                  aiComponent_CAMERAS | aiComponent_MATERIALS);
  const unsigned flags = aiProcess_RemoveComponent | aiProcess_Triangulate | aiProcess_PreTransformVertices |
                         aiProcess_SortByPType;
  const aiScene* scene = importer.ReadFile(path.string(), flags);
  if (!scene) {
    throw MeshLoadError("cannot load " + describe(path) + ": " +
                        std::string(importer.GetErrorString()));
  }

  // Weld across assimp meshes (an OBJ with several objects or materials gives several).
  MeshBuilder builder(path, result.mesh);
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* am = scene->mMeshes[m];
    std::vector<Eigen::Vector3f> positions(am->mNumVertices);
    for (unsigned v = 0; v < am->mNumVertices; ++v)
      positions[v] = Eigen::Vector3f(am->mVertices[v].x, am->mVertices[v].y, am->mVertices[v].z);
    const std::vector<int> remap = builder.add_vertices(positions);
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
      const aiFace& face = am->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines carry no surface
      builder.add_triangle(remap[face.mIndices[0]], remap[face.mIndices[1]], remap[face.mIndices[2]]);
    }
  }
  return finish(path, std::move(result), builder.skipped_degenerate);
}

TriangleMesh load_mesh(const std::filesystem::path& path) {
  return load_mesh_with_warnings(path).mesh;
}

void write_ply(const TriangleMesh& mesh, const std::filesystem::path& path) {
  static_assert(std::endian::native == std::endian::little, "PLY writer assumes little endian");
  // assimp 5.2.5 (and readers like it) take a first data byte of 0x0A for the end of the header
  // line and then read past their buffers. That byte is the lowest byte of the first vertex's x:
  // put first a vertex whose x does not start so. With none (every x starts with 0x0A, as in
  // crafted files), the file is written as ASCII, which every reader takes.
  const auto first_byte = [](const Eigen::Vector3f& v) {
    unsigned char b[4];
    std::memcpy(b, v.data(), 4);
    return b[0];
  };
  std::size_t first = 0;
  while (first < mesh.vertices.size() && first_byte(mesh.vertices[first]) == '\n') ++first;
  const bool ascii = first == mesh.vertices.size() && !mesh.vertices.empty();
  // Vertex order written: `first` and 0 swapped.
  const auto written = [&](std::size_t i) { return i == 0 ? first : i == first ? 0 : i; };

  std::ofstream out(path, std::ios::binary);
  if (!out) throw std::runtime_error("cannot write PLY '" + path.string() + "'");
  out << "ply\nformat " << (ascii ? "ascii" : "binary_little_endian") << " 1.0\ncomment written by fba_geometry\n"
      << "element vertex " << mesh.vertices.size() << "\n"
      << "property float x\nproperty float y\nproperty float z\n"
      << "element face " << mesh.triangles.size() << "\n"
      << "property list uchar int vertex_indices\nend_header\n";
  if (ascii) {
    char buf[64];
    const auto put = [&](float x, char sep) {
      char* end = std::to_chars(buf, buf + sizeof buf, x).ptr;  // the shortest text that reads back exactly
      *end++ = sep;
      out.write(buf, end - buf);
    };
    for (const auto& v : mesh.vertices) put(v.x(), ' '), put(v.y(), ' '), put(v.z(), '\n');
    for (const auto& t : mesh.triangles) out << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
  } else {
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
      out.write(reinterpret_cast<const char*>(mesh.vertices[written(i)].data()), 12);
    for (const auto& t : mesh.triangles) {
      const unsigned char three = 3;
      std::int32_t idx[3];
      for (int k = 0; k < 3; ++k) idx[k] = static_cast<std::int32_t>(written(static_cast<std::size_t>(t[k])));
      out.write(reinterpret_cast<const char*>(&three), 1);
      out.write(reinterpret_cast<const char*>(idx), 12);
    }
  }
  if (!out) throw std::runtime_error("error while writing PLY '" + path.string() + "'");
}

Eigen::AlignedBox3d mesh_bounds(const TriangleMesh& mesh) {
  Eigen::AlignedBox3d box;  // default-constructed: empty
  for (const auto& v : mesh.vertices) box.extend(v.cast<double>());
  return box;
}

namespace {

// The sum of f(a, b, c) over the mesh's triangles, their corners a, b, c in double.
template <class F>
double sum_over_triangles(const TriangleMesh& mesh, F f) {
  double sum = 0;
  for (const auto& t : mesh.triangles)
    sum += f(mesh.vertices[t[0]].cast<double>(), mesh.vertices[t[1]].cast<double>(), mesh.vertices[t[2]].cast<double>());
  return sum;
}

}  // namespace

double signed_volume(const TriangleMesh& mesh) {
  const double six_v = sum_over_triangles(mesh, [](const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
    return a.dot(b.cross(c));
  });
  return six_v / 6.0;
}

double surface_area(const TriangleMesh& mesh) {
  const double twice = sum_over_triangles(mesh, [](const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
    return (b - a).cross(c - a).norm();
  });
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
