// PLY files written by fba are read by every reader, assimp 5.2.5 included (it takes a first data
// byte of 0x0A for the end of the header line and then reads past its buffers), and PLY files
// are read with validation: a file that is truncated, or whose header lies, is an error naming
// what was expected and found, never a crash or a huge allocation.
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>

#include <assimp/Importer.hpp>
#include <assimp/scene.h>
#include <gtest/gtest.h>

#include "fba/geometry/mesh_io.hpp"
#include "load_error.hpp"
#include "support/child_process.hpp"
#include "support/geometry_checks.hpp"

namespace fba::geometry {
namespace {

using test::load_error;
using test::TempDir;

// A float near x whose lowest byte (the first byte written, little endian) is 0x0A.
float with_first_byte_newline(float x) {
  unsigned char b[4];
  std::memcpy(b, &x, 4);
  b[0] = 0x0A;
  std::memcpy(&x, b, 4);
  return x;
}

std::string file_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The body's first byte: what assimp 5.2.5 misreads when it is 0x0A.
unsigned char first_data_byte(const std::filesystem::path& p) {
  const std::string s = file_bytes(p);
  const std::string marker = "end_header\n";
  const auto at = s.find(marker);
  EXPECT_NE(at, std::string::npos);
  return static_cast<unsigned char>(s.at(at + marker.size()));
}

// Whether assimp reads the file to `triangles` triangles, in a child process: on a misread
// file it crashes or aborts, which must not take the test down.
bool assimp_reads(const std::filesystem::path& p, std::size_t triangles) {
  const auto read = fba::test::in_child_process([&] {
    Assimp::Importer importer;
    const aiScene* scene = importer.ReadFile(p.string(), 0);
    return scene && scene->mNumMeshes == 1 && scene->mMeshes[0]->mNumFaces == triangles ? 0 : 1;
  });
  return read.status == 0;
}

// A box whose first vertex's x encodes with 0x0A first, as a carved model's can.
TriangleMesh box_with_newline_first_vertex() {
  TriangleMesh box = make_box({-0.08, -0.05, 0.0}, {0.07, 0.06, 0.1});
  box.vertices[0].x() = with_first_byte_newline(box.vertices[0].x());
  return box;
}

void expect_same_geometry(const TriangleMesh& read, const TriangleMesh& written) {
  EXPECT_EQ(read.triangles.size(), written.triangles.size());
  EXPECT_EQ(read.vertices.size(), written.vertices.size());
  EXPECT_DOUBLE_EQ(signed_volume(read), signed_volume(written));
  EXPECT_TRUE(mesh_bounds(read).isApprox(mesh_bounds(written), 0.0));
}

void write_bytes(const std::filesystem::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

TEST(Ply, WrittenModelNeverStartsItsDataWithANewlineByte) {
  TempDir dir;
  const TriangleMesh box = box_with_newline_first_vertex();
  const auto path = dir.path() / "box.ply";
  write_ply(box, path);
  EXPECT_NE(first_data_byte(path), 0x0A);
  EXPECT_NE(file_bytes(path).find("format binary_little_endian"), std::string::npos);
  expect_same_geometry(load_mesh(path), box);
  EXPECT_TRUE(assimp_reads(path, box.triangles.size()));
}

TEST(Ply, ModelWhoseEveryXStartsWithANewlineByteIsWrittenAsAscii) {
  TempDir dir;
  TriangleMesh box = make_box({-0.08, -0.05, 0.0}, {0.07, 0.06, 0.1});
  for (auto& v : box.vertices) v.x() = with_first_byte_newline(v.x());
  const auto path = dir.path() / "box.ply";
  write_ply(box, path);
  EXPECT_NE(file_bytes(path).find("format ascii 1.0"), std::string::npos);
  expect_same_geometry(load_mesh(path), box);  // the shortest exact text: the same floats
  EXPECT_TRUE(assimp_reads(path, box.triangles.size()));
}

// A file written the old way (first data byte 0x0A) is valid PLY, and fba reads it.
TEST(Ply, ValidBinaryFileWhoseDataStartsWithANewlineByteIsRead) {
  TempDir dir;
  const TriangleMesh box = box_with_newline_first_vertex();
  std::string bytes = "ply\nformat binary_little_endian 1.0\nelement vertex 8\nproperty float x\nproperty float y\n"
                      "property float z\nelement face 12\nproperty list uchar int vertex_indices\nend_header\n";
  for (const auto& v : box.vertices) bytes.append(reinterpret_cast<const char*>(v.data()), 12);
  for (const auto& t : box.triangles) {
    bytes.push_back(3);
    bytes.append(reinterpret_cast<const char*>(t.data()), 12);
  }
  const auto path = dir.path() / "old.ply";
  write_bytes(path, bytes);
  ASSERT_EQ(first_data_byte(path), 0x0A);
  expect_same_geometry(load_mesh(path), box);
}

TEST(Ply, TruncatedFileIsAnErrorGivingTheSizes) {
  TempDir dir;
  const auto path = dir.path() / "box.ply";
  write_ply(make_box({0, 0, 0}, {1, 1, 1}), path);
  std::string bytes = file_bytes(path);
  bytes.resize(bytes.size() - 20);
  write_bytes(path, bytes);
  const std::string what = load_error(path);
  EXPECT_NE(what.find("box.ply"), std::string::npos) << what;
  EXPECT_NE(what.find("expected 12 'face' elements, found the end of the file"), std::string::npos) << what;
}

TEST(Ply, TrailingBytesAfterTheElementsAreAnError) {
  TempDir dir;
  const auto path = dir.path() / "box.ply";
  write_ply(make_box({0, 0, 0}, {1, 1, 1}), path);
  write_bytes(path, file_bytes(path) + "xyz");
  EXPECT_NE(load_error(path).find("found 3 more bytes"), std::string::npos);
}

// Files refused for what their bytes say, each with an error that names the fault (the counts
// beyond the file's size before anything is read).
TEST(Ply, MalformedFilesAreRefusedNamingTheFault) {
  struct Case {
    const char* name;
    std::string bytes;
    const char* error;
  };
  const Case cases[] = {
      {"header counts beyond the file's size",
       "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\n"
       "property float z\nend_header\n" + std::string(24, '\1'),
       "declares 4000000000 'vertex' elements of at least 12 bytes each, but the data after the header is 24 bytes"},
      {"a face naming a missing vertex",
       "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n",
       "face 0 names vertex 7, but there are 3 vertices"},
      {"a header without its end", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n", "expected 'end_header'"},
      {"an unknown scalar type", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float128 x\nend_header\n",
       "line 4: expected a PLY scalar type"},
      {"a word for a number",
       "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 zero 0\n",
       "line 8: expected a number in 'vertex' element 0, found 'zero'"},
  };
  TempDir dir;
  const auto path = dir.path() / "bad.ply";
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    write_bytes(path, c.bytes);
    const std::string what = load_error(path);
    EXPECT_NE(what.find(c.error), std::string::npos) << what;
  }
}

// Other writers' PLY: big endian, double coordinates, extra properties and quads.
TEST(Ply, BigEndianDoublesExtraPropertiesAndQuadsAreRead) {
  TempDir dir;
  const auto path = dir.path() / "quad.ply";
  std::string bytes = "ply\nformat binary_big_endian 1.0\ncomment a unit square\nelement vertex 4\nproperty double x\n"
                      "property double y\nproperty double z\nproperty uchar red\nelement face 1\n"
                      "property list uchar uint vertex_indices\nproperty float quality\nend_header\n";
  const auto be = [&](const void* p, int n) {
    const auto* b = static_cast<const char*>(p);
    for (int i = n - 1; i >= 0; --i) bytes.push_back(b[i]);
  };
  const double xy[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (const auto& v : xy) {
    const double z = 0.5;
    be(&v[0], 8), be(&v[1], 8), be(&z, 8);
    bytes.push_back(static_cast<char>(200));
  }
  bytes.push_back(4);
  for (std::uint32_t i = 0; i < 4; ++i) be(&i, 4);
  const float quality = 1;
  be(&quality, 4);
  write_bytes(path, bytes);
  const TriangleMesh m = load_mesh(path);
  ASSERT_EQ(m.triangles.size(), 2u);
  EXPECT_TRUE(mesh_bounds(m).isApprox(Eigen::AlignedBox3d(Eigen::Vector3d(0, 0, 0.5), Eigen::Vector3d(1, 1, 0.5)), 0.0));
  EXPECT_NEAR(surface_area(m), 1.0, 1e-12);
}

}  // namespace
}  // namespace fba::geometry
