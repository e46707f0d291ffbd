#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <utility>

#include <gtest/gtest.h>

#include "fba/geometry/mesh_io.hpp"
#include "load_error.hpp"
#include "support/geometry_checks.hpp"

namespace fba::geometry {
namespace {

using test::load_error;
using test::TempDir;

// Every undirected edge of a closed manifold mesh is used by exactly two triangles, once in each
// direction.
bool closed_and_consistently_oriented(const TriangleMesh& mesh) {
  std::map<std::pair<int, int>, int> directed;
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
  for (const auto& [edge, count] : directed) {
    if (count != 1) return false;
    auto it = directed.find({edge.second, edge.first});
    if (it == directed.end() || it->second != 1) return false;
  }
  return true;
}

class YcbMesh : public ::testing::TestWithParam<const char*> {};

TEST_P(YcbMesh, LoadsAllTrianglesWithSaneBoundsDespiteMissingMaterialLibrary) {
  const auto path = test::ycb_mesh(GetParam());
  MeshLoadResult r;
  ASSERT_NO_THROW(r = load_mesh_with_warnings(path));
  EXPECT_NEAR(static_cast<double>(r.mesh.triangles.size()), 15728, 100);
  // The missing .mtl is reported, not fatal.
  ASSERT_FALSE(r.warnings.empty());
  EXPECT_NE(r.warnings.front().find(".mtl"), std::string::npos) << r.warnings.front();
  const auto box = mesh_bounds(r.mesh);
  const Eigen::Vector3d size = box.sizes();
  EXPECT_GT(size.minCoeff(), 0.01) << "a YCB object is more than a centimetre thick";
  EXPECT_LT(size.maxCoeff(), 0.40) << "metres, not millimetres";
  EXPECT_LT(box.center().norm(), 0.2) << "origin near the object";
  EXPECT_GT(signed_volume(r.mesh), 0.0) << "outward triangles";
}

TEST_P(YcbMesh, WeldedSurfaceIsClosedAndConsistentlyOriented) {
  const TriangleMesh mesh = load_mesh(test::ycb_mesh(GetParam()));
  EXPECT_TRUE(closed_and_consistently_oriented(mesh));
}

INSTANTIATE_TEST_SUITE_P(Ycb, YcbMesh, ::testing::ValuesIn(test::kYcbNames));

TEST(MeshIo, MissingFileThrowsNamingFileAndReason) {
  const std::string what = load_error("/nonexistent/dir/no-such-mesh.obj");
  EXPECT_NE(what.find("no-such-mesh.obj"), std::string::npos) << what;
  EXPECT_NE(what.find("does not exist"), std::string::npos) << what;
}

TEST(MeshIo, GarbageFileThrowsNamingFile) {
  TempDir dir;
  for (const char* name : {"garbage.ply", "garbage.stl", "garbage.obj", "garbage.xyz123"}) {
    const auto path = dir.path() / name;
    {
      std::ofstream out(path, std::ios::binary);
      for (int i = 0; i < 4096; ++i) out.put(static_cast<char>((i * 7919 + 13) % 251));
    }
    const std::string what = load_error(path);
    EXPECT_NE(what.find(name), std::string::npos) << what;
  }
}

TEST(MeshIo, EmptyFileThrows) {
  TempDir dir;
  const auto path = dir.path() / "empty.obj";
  std::ofstream(path).close();
  EXPECT_THROW(load_mesh(path), MeshLoadError);
}

TEST(MeshIo, DirectoryThrows) {
  TempDir dir;
  EXPECT_THROW(load_mesh(dir.path()), MeshLoadError);
}

// Refused from its size alone: the file is sparse, and reading it would take its whole size.
TEST(MeshIo, AFileOverTheSizeLimitIsRefusedNamingItsSizeAndTheLimit) {
  TempDir dir;
  const auto path = dir.path() / "huge.obj";
  std::ofstream(path).close();
  std::filesystem::resize_file(path, kMaxMeshFileBytes + 1);
  const std::string what = load_error(path);
  EXPECT_NE(what.find("huge.obj"), std::string::npos) << what;
  EXPECT_NE(what.find("the file is 128.0 MiB (" + std::to_string(kMaxMeshFileBytes + 1) + " bytes)"), std::string::npos) << what;
  EXPECT_NE(what.find("more than the 128.0 MiB a mesh file may have"), std::string::npos) << what;
}

// Copies of a vertex are one, written as -0 or 0 alike (the tetrahedron is closed); a vertex a
// hair apart is another.
TEST(MeshIo, VerticesAreWeldedByExactPositionOnly) {
  TempDir dir;
  const std::string closed = dir.file("closed.obj",
                                      "v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0 0 0.1\nv -0.0 0 0\nv 0.1 0 0\n"
                                      "f 1 3 2\nf 5 2 4\nf 1 4 3\nf 6 3 4\n");
  const TriangleMesh mesh = load_mesh(closed);
  EXPECT_EQ(mesh.vertices.size(), 4u);
  EXPECT_TRUE(closed_and_consistently_oriented(mesh));
  const std::string apart = dir.file("apart.obj",
                                     "v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0 0 0.1\nv 0.0000001 0 0\n"
                                     "f 1 3 2\nf 5 2 4\nf 1 4 3\nf 2 3 4\n");
  EXPECT_EQ(load_mesh(apart).vertices.size(), 5u);
}

TEST(MeshIo, WritePlyRoundTripsGeometry) {
  TempDir dir;
  const TriangleMesh sphere = make_uv_sphere({0.1, -0.2, 0.3}, 0.05, 24, 12);
  const auto path = dir.path() / "sphere.ply";
  write_ply(sphere, path);
  const MeshLoadResult r = load_mesh_with_warnings(path);
  EXPECT_TRUE(r.warnings.empty());
  EXPECT_EQ(r.mesh.triangles.size(), sphere.triangles.size());
  EXPECT_EQ(r.mesh.vertices.size(), sphere.vertices.size());
  EXPECT_NEAR(signed_volume(r.mesh), signed_volume(sphere), 1e-9);
  EXPECT_TRUE(mesh_bounds(r.mesh).isApprox(mesh_bounds(sphere), 1e-6));
}

TEST(MeshIo, BoxHasExactVolumeAreaAndIsClosed) {
  const TriangleMesh box = make_box({-0.1, 0.0, 0.2}, {0.3, 0.5, 0.4});
  EXPECT_NEAR(signed_volume(box), 0.4 * 0.5 * 0.2, 1e-7);
  EXPECT_NEAR(surface_area(box), 2 * (0.4 * 0.5 + 0.5 * 0.2 + 0.4 * 0.2), 1e-6);
  EXPECT_TRUE(closed_and_consistently_oriented(box));
  EXPECT_TRUE(closed_and_consistently_oriented(make_uv_sphere({0, 0, 0}, 1.0, 16, 8)));
}

TEST(MeshIo, CubeAroundContainsBoxAndIsCube) {
  const Eigen::AlignedBox3d box(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 2, 0.5));
  const auto cube = cube_around(box, 0.1);
  EXPECT_NEAR(cube.sizes().x(), 2.4, 1e-12);
  EXPECT_NEAR(cube.sizes().y(), 2.4, 1e-12);
  EXPECT_NEAR(cube.sizes().z(), 2.4, 1e-12);
  EXPECT_TRUE(cube.contains(box));
  EXPECT_TRUE(cube.center().isApprox(box.center()));
}

}  // namespace
}  // namespace fba::geometry
