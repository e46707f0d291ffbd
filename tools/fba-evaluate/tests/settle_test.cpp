// Settling an object on the table in MuJoCo (tools/fba-evaluate/settle.hpp): it comes to rest where
// it would, still, on its lowest points, its centre of mass over what it stands on, and a second drop
// from there leaves it there; the same drop rests the same way.
#include <algorithm>
#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include "fba/geometry/convex_hull.hpp"
#include "fba/geometry/object_families.hpp"
#include "settle.hpp"

namespace fba::evaluate {
namespace {

using geometry::ConvexPart;
using geometry::FamilyObject;

FamilyObject box_object(double sx, double sy, double sz) {
  FamilyObject o;
  o.mesh = geometry::make_box_shape(sx, sy, sz);
  ConvexPart p;
  p.kind = ConvexPart::Kind::box;
  p.half = Eigen::Vector3d(sx, sy, sz) / 2;
  o.parts = {p};
  return o;
}

FamilyObject cylinder_object(double r, double h) {
  FamilyObject o;
  o.mesh = geometry::make_cylinder_shape(r, h);
  ConvexPart p;
  p.kind = ConvexPart::Kind::cylinder;
  p.half = Eigen::Vector3d(r, r, h / 2);
  o.parts = {p};
  return o;
}

Eigen::Vector3d up_in_object(const SettleResult& r) { return r.settled.conjugate() * Eigen::Vector3d::UnitZ(); }

double degrees_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180 / std::numbers::pi;
}

TEST(Settle, ABoxRestsOnAFaceWhicheverWayItIsDropped) {
  const FamilyObject box = box_object(0.10, 0.06, 0.03);
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    const SettleResult r = settle(box.mesh, box.parts, random_orientation(seed));
    SCOPED_TRACE("drop " + std::to_string(seed));
    EXPECT_TRUE(r.still);
    const Eigen::Vector3d up = up_in_object(r);
    int axis = 0;
    up.cwiseAbs().maxCoeff(&axis);
    EXPECT_LT(degrees_between(up.cwiseAbs(), Eigen::Vector3d::Unit(axis)), 0.5) << up.transpose();
    // On the table: its lowest point at z = 0 but for the soft contact's depth, its centre half the
    // size along its up axis above it.
    EXPECT_LT(r.lowest, 0.0005);
    EXPECT_GT(r.lowest, -0.002);
    EXPECT_NEAR(r.position.z() - r.lowest, Eigen::Vector3d(0.10, 0.06, 0.03)[axis] / 2, 0.0005);
    EXPECT_TRUE(r.warnings.empty());
  }
}

// A rod lies on its side. A disc lies on a face or stands on its rim, its axis level (the rim's line
// contact, as wide as the disc is thick, holds it), and nowhere between.
TEST(Settle, ALongCylinderLiesOnItsSideAndADiscOnAFaceOrItsRim) {
  const FamilyObject rod = cylinder_object(0.01, 0.12), disc = cylinder_object(0.05, 0.015);
  int flat = 0;
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    SCOPED_TRACE("drop " + std::to_string(seed));
    const SettleResult lying = settle(rod.mesh, rod.parts, random_orientation(seed));
    EXPECT_TRUE(lying.still);
    EXPECT_NEAR(degrees_between(up_in_object(lying), Eigen::Vector3d::UnitZ()), 90, 0.5);
    const SettleResult resting = settle(disc.mesh, disc.parts, random_orientation(seed));
    EXPECT_TRUE(resting.still);
    const double tilt = degrees_between(up_in_object(resting).cwiseAbs(), Eigen::Vector3d::UnitZ());
    EXPECT_TRUE(tilt < 0.5 || std::abs(tilt - 90) < 0.5) << tilt << " degrees";
    flat += tilt < 0.5;
  }
  EXPECT_GE(flat, 1);
}

// How far q lies outside the convex polygon (0 inside); a polygon of one or two points is a point
// or a segment.
double outside(const std::vector<Eigen::Vector2d>& poly, const Eigen::Vector2d& q) {
  const auto to_segment = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    const Eigen::Vector2d ab = b - a;
    const double t = ab.squaredNorm() > 0 ? std::clamp((q - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
    return (a + t * ab - q).norm();
  };
  if (poly.size() == 1) return (poly[0] - q).norm();
  bool inside = poly.size() >= 3;
  double nearest = INFINITY;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Eigen::Vector2d& a = poly[i];
    const Eigen::Vector2d& b = poly[(i + 1) % poly.size()];
    nearest = std::min(nearest, to_segment(a, b));
    if ((b - a).x() * (q - a).y() - (b - a).y() * (q - a).x() < 0) inside = false;
  }
  return inside ? 0 : nearest;
}

// A stable pose, for two objects of each family dropped twice: the object is still, its centre of
// mass lies over the polygon of the points it stands on (the mesh's within 1 mm of its lowest), and
// dropped again from there (1 mm above the table) it stays within a degree of the same pose.
TEST(Settle, EveryFamilyComesToAStablePose) {
  for (geometry::ObjectFamily f : geometry::all_families())
    for (int i = 0; i < 2; ++i) {
      const FamilyObject o = geometry::make_family_object(f, 31, i);
      const Eigen::Vector3d centroid = geometry::solid_properties(o.mesh).centroid;
      for (std::uint64_t drop = 0; drop < 2; ++drop) {
        SCOPED_TRACE(o.name + " drop " + std::to_string(drop));
        const SettleResult r = settle(o.mesh, o.parts, random_orientation(o.seed + drop));
        EXPECT_TRUE(r.still);
        EXPECT_TRUE(r.warnings.empty());
        const Eigen::Matrix3d rot = r.settled.toRotationMatrix();
        std::vector<Eigen::Vector2d> support;
        for (const auto& v : o.mesh.vertices) {
          const Eigen::Vector3d w = rot * v.cast<double>() + r.position;
          if (w.z() < r.lowest + 0.001) support.push_back(w.head<2>());
        }
        const Eigen::Vector3d com = rot * centroid + r.position;
        EXPECT_LT(outside(fba::geometry::convex_hull_2d(support), com.head<2>()), 0.001) << support.size() << " points of support";
        SettleParams again;
        again.drop_height = 0.001;
        const SettleResult second = settle(o.mesh, o.parts, r.settled, again);
        EXPECT_TRUE(second.still);
        EXPECT_LT(degrees_between(up_in_object(second), up_in_object(r)), 1.0);
      }
    }
}

TEST(Settle, TheSameDropComesToTheSameRest) {
  const FamilyObject o = geometry::make_family_object(geometry::ObjectFamily::tool, 4, 2);
  const SettleResult a = settle(o.mesh, o.parts, random_orientation(99)), b = settle(o.mesh, o.parts, random_orientation(99));
  EXPECT_EQ(a.settled.coeffs(), b.settled.coeffs());
  EXPECT_EQ(a.position, b.position);
  EXPECT_EQ(a.steps, b.steps);
}

// Without parts the mesh collides as its hull: a box mesh alone rests on a face too.
TEST(Settle, AMeshWithoutPartsCollidesAsItsHull) {
  const TriangleMesh box = geometry::make_box_shape(0.08, 0.05, 0.02);
  const SettleResult r = settle(box, {}, random_orientation(3));
  EXPECT_TRUE(r.still);
  const Eigen::Vector3d up = up_in_object(r).cwiseAbs();
  EXPECT_GT(up.maxCoeff(), std::cos(0.5 * std::numbers::pi / 180));
}

TEST(Settle, AMeshWithoutVolumeIsRefused) {
  TriangleMesh inside_out = geometry::make_box_shape(0.05, 0.05, 0.05);
  for (auto& t : inside_out.triangles) std::swap(t[1], t[2]);
  try {
    settle(inside_out, {}, Eigen::Quaterniond::Identity());
    ADD_FAILURE() << "not refused";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("expected a closed, outward mesh"), std::string::npos) << e.what();
  }
}

// Drawn uniformly over the rotations (their up directions spread evenly over the sphere), the same
// for the same seed on any machine.
TEST(Settle, RandomOrientationsAreUniformAndTheSameForTheSameSeed) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  int upper = 0;
  constexpr int n = 4000;
  for (int s = 0; s < n; ++s) {
    const Eigen::Vector3d up = random_orientation(static_cast<std::uint64_t>(s)) * Eigen::Vector3d::UnitZ();
    mean += up / n;
    upper += up.z() > 0.5;  // a cap of a quarter of the sphere's area
  }
  EXPECT_LT(mean.norm(), 0.05);
  EXPECT_NEAR(upper, n / 4, 4 * std::sqrt(n * 0.25 * 0.75));
  EXPECT_EQ(random_orientation(7).coeffs(), random_orientation(7).coeffs());
  EXPECT_NE(random_orientation(7).coeffs(), random_orientation(8).coeffs());
  EXPECT_NEAR(random_orientation(7).norm(), 1, 1e-12);
}

// The tilt alone: it takes the direction that is up to +z, and differs from the orientation by a
// turn about the vertical.
TEST(Settle, TiltOnlyLeavesOutTheTurnAboutTheVertical) {
  for (std::uint64_t s = 1; s <= 20; ++s) {
    const Eigen::Quaterniond q = random_orientation(s), t = tilt_only(q);
    EXPECT_LT((t * (q.conjugate() * Eigen::Vector3d::UnitZ()) - Eigen::Vector3d::UnitZ()).norm(), 1e-12);
    const Eigen::Quaterniond turn = q * t.conjugate();
    EXPECT_LT((turn * Eigen::Vector3d::UnitZ() - Eigen::Vector3d::UnitZ()).norm(), 1e-12);
  }
}

}  // namespace
}  // namespace fba::evaluate
