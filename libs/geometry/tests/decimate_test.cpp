// Decimation by vertex clustering: within the bound asked for, and the shape kept within a cube of
// the grid.
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <gtest/gtest.h>

#include "fba/geometry/decimate.hpp"
#include "fba/geometry/mesh_io.hpp"

namespace fba::geometry {
namespace {

TEST(Decimate, AMeshWithinTheBoundIsReturnedAsItIs) {
  const TriangleMesh sphere = make_uv_sphere({0, 0, 0}, 0.05, 32, 16);
  const Decimated d = decimate(sphere, sphere.triangles.size());
  EXPECT_EQ(d.cell, 0.0);
  EXPECT_EQ(d.mesh.vertices, sphere.vertices);
  EXPECT_EQ(d.mesh.triangles, sphere.triangles);
}

TEST(Decimate, AFineSphereIsBroughtWithinTheBoundAndKeepsItsShape) {
  constexpr double r = 0.04;
  const Eigen::Vector3d centre(0.01, -0.02, 0.04);
  const TriangleMesh sphere = make_uv_sphere(centre, r, 400, 300);
  ASSERT_GT(sphere.triangles.size(), 200000u);
  const Decimated d = decimate(sphere, 50000);
  EXPECT_LE(d.mesh.triangles.size(), 50000u);
  EXPECT_GT(d.mesh.triangles.size(), 10000u) << "the grid is coarser than it needs to be";
  ASSERT_GT(d.cell, 0.0);
  const double diagonal = d.cell * std::sqrt(3.0);
  for (const auto& v : d.mesh.vertices) EXPECT_NEAR((v.cast<double>() - centre).norm(), r, diagonal);
  EXPECT_TRUE(mesh_bounds(d.mesh).isApprox(mesh_bounds(sphere), diagonal / r));
  EXPECT_NEAR(signed_volume(d.mesh), 4.0 / 3.0 * std::numbers::pi * r * r * r, 0.02 * signed_volume(sphere));
}

TEST(Decimate, VerticesInCubesOfTheirOwnStayWhereTheyAre) {
  const TriangleMesh box = make_box({0, 0, 0}, {0.1, 0.2, 0.3});
  const TriangleMesh same = cluster_vertices(box, 0.05);
  EXPECT_EQ(same.vertices, box.vertices);
  EXPECT_EQ(same.triangles, box.triangles);
  // In one cube the whole box is a point: no triangle is left.
  EXPECT_TRUE(cluster_vertices(box, 1.0).triangles.empty());
}

TEST(Decimate, ACellThatIsNotPositiveIsRefused) {
  const TriangleMesh box = make_box({0, 0, 0}, {0.1, 0.1, 0.1});
  EXPECT_THROW(cluster_vertices(box, 0), std::invalid_argument);
  EXPECT_THROW(cluster_vertices(box, -1), std::invalid_argument);
  EXPECT_THROW(decimate(box, 0), std::invalid_argument);
}

}  // namespace
}  // namespace fba::geometry
