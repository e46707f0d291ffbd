// The object families (issue 31): every mesh one closed, consistently outward surface of positive
// volume that reads back closed from an OBJ, the volume its parameters give, within the documented
// ranges and the grasp task's workspace, the same for the same seed.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>
#include <string>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "fba/geometry/mesh_io.hpp"
#include "fba/geometry/object_families.hpp"
#include "support/mesh_files.hpp"
#include "support/geometry_checks.hpp"

namespace fba::geometry::test {
namespace {

using std::numbers::pi;

struct ObjectCase {
  ObjectFamily family;
  std::uint64_t seed;
  int index;
};

std::vector<ObjectCase> many_objects() {
  std::vector<ObjectCase> out;
  for (ObjectFamily f : all_families())
    for (std::uint64_t seed : {1ULL, 20261201ULL})
      for (int i = 0; i < 12; ++i) out.push_back({f, seed, i});
  return out;
}

TEST(ObjectFamilies, EveryObjectIsOneClosedOutwardSurfaceCentredWithinTheRadius) {
  for (const auto& c : many_objects()) {
    const FamilyObject o = make_family_object(c.family, c.seed, c.index);
    SCOPED_TRACE(o.name + " of seed " + std::to_string(c.seed));
    EXPECT_EQ(closed_surface_fault(o.mesh), "");
    const double volume = signed_volume(o.mesh);
    EXPECT_GT(volume, 1e-6);  // positive: the triangles face outward
    EXPECT_NEAR(solid_properties(o.mesh).volume, volume, 1e-9 * std::max(1.0, volume));
    const auto box = mesh_bounds(o.mesh);
    EXPECT_LT(box.center().norm(), 1e-6);
    double r = 0;
    for (const auto& v : o.mesh.vertices) r = std::max(r, v.cast<double>().norm());
    EXPECT_LE(r, kMaxObjectRadius);
  }
}

// load_mesh welds vertices by position and drops degenerate triangles: a file written from the mesh
// must read back as the same closed surface (distinct vertices stay distinct through the OBJ's text).
TEST(ObjectFamilies, EveryObjectReadsBackFromAnObjAsTheSameClosedSurface) {
  const TempDir dir;
  for (ObjectFamily f : all_families())
    for (int i = 0; i < 4; ++i) {
      const FamilyObject o = make_family_object(f, 5, i);
      SCOPED_TRACE(o.name);
      const auto path = dir.path() / (o.name + ".obj");
      fba::test::write_obj(o.mesh, path);
      const TriangleMesh back = load_mesh(path);
      EXPECT_EQ(back.vertices.size(), o.mesh.vertices.size());
      EXPECT_EQ(back.triangles.size(), o.mesh.triangles.size());
      EXPECT_EQ(closed_surface_fault(back), "");
      EXPECT_NEAR(signed_volume(back), signed_volume(o.mesh), 1e-12);
    }
}

double param(const FamilyObject& o, const std::string& key) {
  for (const auto& [k, v] : o.parameters)
    if (k == key) return v;
  ADD_FAILURE() << o.name << " has no parameter " << key;
  return NAN;
}

// The volume the parameters give, for the shapes as built (polygons where the shape is one).
double polygon_area(int sides, double r) { return sides / 2.0 * r * r * std::sin(2 * pi / sides); }

TEST(ObjectFamilies, VolumesAreWhatTheParametersGive) {
  for (int i = 0; i < 6; ++i) {
    const auto box = make_family_object(ObjectFamily::box, 3, i);
    EXPECT_NEAR(signed_volume(box.mesh), param(box, "size_x") * param(box, "size_y") * param(box, "size_z"), 1e-9) << box.name;
    const auto cyl = make_family_object(ObjectFamily::cylinder, 3, i);
    EXPECT_NEAR(signed_volume(cyl.mesh), polygon_area(64, param(cyl, "radius")) * param(cyl, "height"), 1e-9) << cyl.name;
    const auto sphere = make_family_object(ObjectFamily::sphere, 3, i);
    const double r = param(sphere, "radius");
    // Its vertices lie on the sphere: a polyhedron inscribed, within 1.5% of the ball.
    EXPECT_LT(signed_volume(sphere.mesh), 4.0 / 3 * pi * r * r * r) << sphere.name;
    EXPECT_GT(signed_volume(sphere.mesh), 0.985 * 4.0 / 3 * pi * r * r * r) << sphere.name;
    const auto ring = make_family_object(ObjectFamily::ring, 3, i);
    const double torus = 2 * pi * pi * param(ring, "major_radius") * param(ring, "tube_radial") * param(ring, "tube_vertical");
    EXPECT_NEAR(signed_volume(ring.mesh), torus, 0.015 * torus) << ring.name;
    const auto l = make_family_object(ObjectFamily::l_shape, 3, i);
    const double l_area = param(l, "length_x") * param(l, "width_x") + param(l, "width_y") * (param(l, "length_y") - param(l, "width_x"));
    EXPECT_NEAR(signed_volume(l.mesh), l_area * param(l, "thickness"), 1e-9) << l.name;
    const auto t = make_family_object(ObjectFamily::t_shape, 3, i);
    const double t_area = param(t, "bar_length") * param(t, "bar_width") + param(t, "stem_length") * param(t, "stem_width");
    EXPECT_NEAR(signed_volume(t.mesh), t_area * param(t, "thickness"), 1e-9) << t.name;
    const auto holed = make_family_object(ObjectFamily::holed, 3, i);
    const double box_v = param(holed, "size_x") * param(holed, "size_y") * param(holed, "size_z");
    if (holed.kind == "square hole") {
      const double s = param(holed, "hole_half_side");
      EXPECT_NEAR(signed_volume(holed.mesh), box_v - 4 * s * s * param(holed, "size_z"), 1e-9) << holed.name;
    } else {
      const double hole = pi * std::pow(param(holed, "hole_radius"), 2) * param(holed, "size_z");
      EXPECT_NEAR(signed_volume(holed.mesh), box_v - hole, 0.01 * hole) << holed.name;
    }
    const auto tool = make_family_object(ObjectFamily::tool, 3, i);
    const double head = param(tool, "head_x") * param(tool, "head_y") * param(tool, "head_z");
    const double handle = pi * std::pow(param(tool, "handle_radius"), 2) * param(tool, "handle_length");
    EXPECT_NEAR(signed_volume(tool.mesh), head + handle, 0.01 * handle) << tool.name;
  }
}

// A superellipsoid's volume: 2 a b c e1 e2 B(e1/2 + 1, e1) B(e2/2, e2/2). The mesh's vertices lie on
// the surface, which is convex: the polyhedron lies inside it, and at 16 x 16 per face within a few
// percent of it (the boxiest, whose edges the lattice rounds off, the furthest).
TEST(ObjectFamilies, SuperquadricsAreInscribedInTheirSurfaceAndCloseToItsVolume) {
  for (int i = 0; i < 12; ++i) {
    const auto o = make_family_object(ObjectFamily::superquadric, 11, i);
    const double e1 = param(o, "exponent_ns"), e2 = param(o, "exponent_ew");
    EXPECT_GE(e1, 0.2);
    EXPECT_LE(e1, 2.0);
    const double v = 2 * param(o, "semi_x") * param(o, "semi_y") * param(o, "semi_z") * e1 * e2 * std::beta(e1 / 2 + 1, e1) *
                     std::beta(e2 / 2, e2 / 2);
    EXPECT_LT(signed_volume(o.mesh), v) << o.name << " e " << e1 << " " << e2;
    EXPECT_GT(signed_volume(o.mesh), 0.93 * v) << o.name << " e " << e1 << " " << e2;
  }
}

// The documented ranges (docs/evaluating-grasps.md), each parameter of each family.
TEST(ObjectFamilies, ParametersLieInTheDocumentedRangesAndKindsAlternate) {
  const std::map<std::string, std::pair<double, double>> ranges = {
      {"block size_x", {0.03, 0.15}},   {"block size_y", {0.03, 0.15}},     {"block size_z", {0.03, 0.15}},
      {"plate size_x", {0.04, 0.15}},   {"plate size_y", {0.04, 0.15}},     {"plate size_z", {0.01, 0.03}},
      {"long radius", {0.01, 0.06}},    {"short radius", {0.01, 0.06}},     {"long height", {0.015, 0.17}},
      {"short height", {0.015, 0.12}},  {"sphere radius", {0.02, 0.07}},    {"ellipsoid semi_x", {0.015, 0.075}},
      {"ellipsoid semi_y", {0.015, 0.075}}, {"ellipsoid semi_z", {0.015, 0.075}}, {"superquadric semi_x", {0.02, 0.065}},
      {"superquadric semi_y", {0.02, 0.065}}, {"superquadric semi_z", {0.02, 0.065}}, {"superquadric exponent_ns", {0.2, 2}},
      {"superquadric exponent_ew", {0.2, 2}}, {"ring major_radius", {0.02, 0.065}}, {"ring tube_radial", {0.01, 0.02}},
      {"ring tube_vertical", {0.005, 0.04}}, {"L length_x", {0.06, 0.15}},   {"L width_x", {0.015, 0.045}},
      {"L length_y", {0.04, 0.12}},     {"L width_y", {0.015, 0.045}},     {"L thickness", {0.015, 0.05}},
      {"T bar_length", {0.06, 0.15}},   {"T bar_width", {0.015, 0.045}},   {"T stem_length", {0.03, 0.10}},
      {"T stem_width", {0.015, 0.045}}, {"T thickness", {0.015, 0.05}},    {"tool handle_radius", {0.008, 0.018}},
      {"tool handle_length", {0.05, 0.12}}, {"tool head_x", {0.015, 0.06}}, {"tool head_y", {0.03, 0.12}},
      {"tool head_z", {0.02, 0.05}},    {"round hole size_x", {0.05, 0.15}}, {"round hole size_y", {0.05, 0.15}},
      {"round hole size_z", {0.015, 0.06}}, {"round hole hole_radius", {0.006, 0.063}}, {"round hole hole_x", {-0.059, 0.059}},
      {"round hole hole_y", {-0.059, 0.059}}, {"square hole size_x", {0.05, 0.15}}, {"square hole size_y", {0.05, 0.15}},
      {"square hole size_z", {0.015, 0.06}}, {"square hole hole_half_side", {0.006, 0.063}}, {"square hole hole_x", {-0.059, 0.059}},
      {"square hole hole_y", {-0.059, 0.059}}};
  std::set<std::string> seen;
  for (const auto& c : many_objects()) {
    const FamilyObject o = make_family_object(c.family, c.seed, c.index);
    for (const auto& [key, v] : o.parameters) {
      const auto r = ranges.find(o.kind + " " + key);
      ASSERT_NE(r, ranges.end()) << o.name << ": " << o.kind << " " << key << " has no documented range";
      EXPECT_GE(v, r->second.first - 1e-12) << o.name << " " << key;
      EXPECT_LE(v, r->second.second + 1e-12) << o.name << " " << key;
      seen.insert(r->first);
    }
    if (c.family == ObjectFamily::box) EXPECT_EQ(o.kind, c.index % 2 ? "plate" : "block");
    if (c.family == ObjectFamily::holed) {
      EXPECT_EQ(o.kind, c.index % 2 ? "square hole" : "round hole");
      // Walls of 1 cm at least around the hole.
      const double size = param(o, c.index % 2 ? "hole_half_side" : "hole_radius");
      EXPECT_GE(param(o, "size_x") / 2 - std::abs(param(o, "hole_x")) - size, 0.01 - 1e-4) << o.name;
      EXPECT_GE(param(o, "size_y") / 2 - std::abs(param(o, "hole_y")) - size, 0.01 - 1e-4) << o.name;
    }
  }
  EXPECT_EQ(seen.size(), ranges.size());  // every family's every parameter was drawn
}

// The grasp task's workspace holds any object at any place the batch list draws (x and y within
// 2.5 cm) turned any way, with 1 cm to spare, as kMaxObjectRadius says.
TEST(ObjectFamilies, TheRadiusLeavesTheGraspTasksWorkspaceAMargin) {
  const YAML::Node task = YAML::LoadFile(fba::test::tasks_dir() + "/grasp.yaml");
  const auto w = task["params"]["workspace"]["default"].as<std::vector<double>>();
  ASSERT_EQ(w.size(), 6u);
  const double offset = 0.025 * std::sqrt(2.0), margin = 0.01;
  for (int a = 0; a < 2; ++a) {
    EXPECT_LE(kMaxObjectRadius + offset + margin, w[a + 3]);
    EXPECT_GE(-kMaxObjectRadius - offset - margin, w[a]);
  }
  EXPECT_LE(2 * kMaxObjectRadius + margin, w[5]);  // standing on the table, z = 0
  EXPECT_LE(w[2], 0.0);
}

TEST(ObjectFamilies, TheSameSeedMakesTheSameObjectAndAnotherSeedAnother) {
  for (ObjectFamily f : all_families()) {
    const auto a = make_family_object(f, 42, 5), b = make_family_object(f, 42, 5), c = make_family_object(f, 43, 5);
    EXPECT_EQ(a.name, std::string(family_name(f)) + "-05");
    EXPECT_EQ(a.parameters, b.parameters);
    ASSERT_EQ(a.mesh.vertices.size(), b.mesh.vertices.size());
    for (std::size_t i = 0; i < a.mesh.vertices.size(); ++i) ASSERT_EQ(a.mesh.vertices[i], b.mesh.vertices[i]);
    EXPECT_NE(a.parameters, c.parameters) << a.name;
    EXPECT_NE(object_seed(42, f, 5), object_seed(42, f, 6));
  }
  // Seeds differ between families at the same index and seed.
  std::set<std::uint64_t> seeds;
  for (ObjectFamily f : all_families()) seeds.insert(object_seed(7, f, 0));
  EXPECT_EQ(seeds.size(), all_families().size());
}

TEST(ObjectFamilies, NamesReadBack) {
  for (ObjectFamily f : all_families()) EXPECT_EQ(family_from_name(family_name(f)), f);
  EXPECT_EQ(family_from_name("boxes"), std::nullopt);
  EXPECT_EQ(all_families().size(), 10u);
}

TEST(ObjectFamilies, ParametersThatGiveNoSolidAreRefusedByName) {
  const auto refused = [](const auto& make, const std::string& says) {
    try {
      make();
      ADD_FAILURE() << "not refused: " << says;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
    }
  };
  refused([] { make_tool_shape(0.02, 0.1, 0.03, 0.03, 0.05); }, "handle narrower than the head's face");
  refused([] { make_holed_box_shape(0.1, 0.1, 0.02, true, 0.04, 0.02, 0); }, "hole inside the box's face");
  refused([] { make_ring_shape(0.01, 0.02, 0.02); }, "major radius above the radial one");
  refused([] { make_l_shape(0.02, 0.02, 0.1, 0.03, 0.02); }, "each bar longer than the other is wide");
  refused([] { make_superquadric_shape(Eigen::Vector3d(0.05, 0.05, 0.05), 2.5, 1); }, "exponents in (0, 2]");
  refused([] { make_box_shape(0.1, 0, 0.1); }, "sizes > 0");
  EXPECT_THROW(make_family_object(ObjectFamily::box, 1, -1), std::invalid_argument);
}

TEST(ObjectFamilies, SolidPropertiesOfABoxAreItsOwn) {
  TriangleMesh m = make_box_shape(0.1, 0.06, 0.02);
  for (auto& v : m.vertices) v += Eigen::Vector3f(0.01f, -0.02f, 0.03f);
  const SolidProperties p = solid_properties(m);
  EXPECT_NEAR(p.volume, 0.1 * 0.06 * 0.02, 1e-6 * 0.1 * 0.06 * 0.02);  // float vertices
  EXPECT_NEAR((p.centroid - Eigen::Vector3d(0.01, -0.02, 0.03)).norm(), 0, 1e-7);
  EXPECT_NEAR(p.inertia(0, 0), (0.06 * 0.06 + 0.02 * 0.02) / 12, 1e-9);
  EXPECT_NEAR(p.inertia(1, 1), (0.1 * 0.1 + 0.02 * 0.02) / 12, 1e-9);
  EXPECT_NEAR(p.inertia(2, 2), (0.1 * 0.1 + 0.06 * 0.06) / 12, 1e-9);
  EXPECT_NEAR(p.inertia(0, 1), 0, 1e-9);
}

// The parts physics collides are the object: every vertex of the mesh lies in a part, and every part
// within the mesh's bounds (0.1 mm either way: the cylinders and spheres are the polygons' circles).
TEST(ObjectFamilies, ConvexPartsAreTheObject) {
  constexpr double tolerance = 1e-4;
  for (ObjectFamily f : all_families())
    for (int i = 0; i < 6; ++i) {
      const FamilyObject o = make_family_object(f, 9, i);
      SCOPED_TRACE(o.name);
      ASSERT_FALSE(o.parts.empty());
      const auto in_part = [&](const ConvexPart& p, const Eigen::Vector3d& v) {
        const Eigen::Vector3d q = p.axes.transpose() * (v - p.centre);
        switch (p.kind) {
          case ConvexPart::Kind::box: return (q.cwiseAbs() - p.half).maxCoeff() <= tolerance;
          case ConvexPart::Kind::cylinder: return q.head<2>().norm() <= p.half.x() + tolerance && std::abs(q.z()) <= p.half.z() + tolerance;
          case ConvexPart::Kind::ellipsoid: return q.cwiseQuotient(p.half + Eigen::Vector3d::Constant(tolerance)).norm() <= 1;
          case ConvexPart::Kind::hull: return std::find(p.points.begin(), p.points.end(), v.cast<float>()) != p.points.end();
        }
        return false;
      };
      for (const auto& v : o.mesh.vertices)
        ASSERT_TRUE(std::any_of(o.parts.begin(), o.parts.end(), [&](const ConvexPart& p) { return in_part(p, v.cast<double>()); }))
            << "vertex " << v.transpose() << " is in no part";
      const Eigen::AlignedBox3d bounds = mesh_bounds(o.mesh);
      for (const auto& p : o.parts) {
        Eigen::AlignedBox3d part;
        if (p.kind == ConvexPart::Kind::hull)
          for (const auto& v : p.points) part.extend(v.cast<double>());
        else
          for (int c = 0; c < 8; ++c)
            part.extend(p.centre + p.axes * Eigen::Vector3d(c & 1 ? 1 : -1, c & 2 ? 1 : -1, c & 4 ? 1 : -1).cwiseProduct(p.half));
        EXPECT_LE(bounds.exteriorDistance(part.min()), tolerance);
        EXPECT_LE(bounds.exteriorDistance(part.max()), tolerance);
        EXPECT_NEAR(p.axes.determinant(), 1, 1e-12);
      }
    }
}

}  // namespace
}  // namespace fba::geometry::test
