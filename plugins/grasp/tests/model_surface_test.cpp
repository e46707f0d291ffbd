// Surface samples of octree models of known shapes: outward normals, the curvature's sign and
// size, and the uncertainty of parts not yet refined.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>

#include "fba/grasp/angles.hpp"
#include "fba/grasp/model_surface.hpp"
#include "fba/grasp/object_surface.hpp"
#include "fba/geometry/mesh_io.hpp"
#include "fba/geometry/renderer.hpp"
#include "fba/geometry/viewpoints.hpp"
#include "fba/vision/contour_extraction.hpp"
#include "support/voxel_shapes.hpp"

namespace fba::grasp {
namespace {

const Eigen::AlignedBox3d kCube(Eigen::Vector3d::Constant(-0.08), Eigen::Vector3d::Constant(0.08));

TEST(ModelSurface, SphereNormalsPointOutwardAndCurvatureIsNearOneOverR) {
  const double r = 0.05;
  const Octree model = test::voxelise(test::sphere_sdf(Eigen::Vector3d::Zero(), r), kCube, 6);  // 2.5 mm leaves
  const ModelSurface s = model_surface(model);
  ASSERT_GT(s.samples.size(), 1000u);
  EXPECT_DOUBLE_EQ(s.finest_edge, 0.16 / 64);
  std::vector<double> angles, curvature;
  for (const auto& x : s.samples) {
    EXPECT_NEAR(x.position.norm(), r, 2 * s.finest_edge);
    angles.push_back(angle_between_deg(x.normal, x.position));
    curvature.push_back(x.curvature);
    EXPECT_FALSE(x.uncertain);
  }
  EXPECT_LT(quantile(angles, 0.5), 5.0);
  EXPECT_LT(quantile(angles, 0.99), 15.0);
  // Mean curvature of a sphere is 1/r = 20 /m: positive (convex) everywhere it is measured.
  EXPECT_NEAR(quantile(curvature, 0.5), 1 / r, 0.3 / r);
  EXPECT_GT(quantile(curvature, 0.05), 0.0);
}

TEST(ModelSurface, BoxFaceNormalsAreTheFaceAxisAndFacesAreFlat) {
  const Eigen::Vector3d size(0.06, 0.08, 0.10);
  const Octree model = test::voxelise(test::box_sdf(Eigen::Vector3d(0.003, -0.002, 0.001), size), kCube, 6);
  const ModelSurface s = model_surface(model);
  ASSERT_GT(s.samples.size(), 500u);
  std::vector<double> curvature;
  int on_faces = 0;
  for (const auto& x : s.samples) {
    // Away from the edges by more than the neighbourhood: on one face.
    const Eigen::Vector3d q = (x.position - Eigen::Vector3d(0.003, -0.002, 0.001)).cwiseAbs() - size / 2;
    int axis;
    q.maxCoeff(&axis);
    Eigen::Vector3d rest = q;
    rest[axis] = -1;
    if (rest.maxCoeff() > -s.radius - s.finest_edge) continue;
    ++on_faces;
    Eigen::Vector3d want = Eigen::Vector3d::Zero();
    want[axis] = x.position[axis] > 0 ? 1 : -1;
    EXPECT_LT(angle_between_deg(x.normal, want), 1.0) << x.position.transpose();
    curvature.push_back(x.curvature);
  }
  ASSERT_GT(on_faces, 200);
  EXPECT_NEAR(quantile(curvature, 0.5), 0.0, 1.0);
  EXPECT_LT(quantile(curvature, 0.95), 5.0);  // a quarter of the sphere's 20 /m below
}

// The two together: what S4 relies on (convex above flat).
TEST(ModelSurface, SphereIsMoreConvexThanABoxFace) {
  const Octree sphere = test::voxelise(test::sphere_sdf(Eigen::Vector3d::Zero(), 0.04), kCube, 6);
  const Octree box = test::voxelise(test::box_sdf(Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(0.08)), kCube, 6);
  auto median = [](const ModelSurface& s) {
    std::vector<double> k;
    for (const auto& x : s.samples) k.push_back(x.curvature);
    return quantile(k, 0.5);
  };
  EXPECT_GT(median(model_surface(sphere)), 10 * std::max(1.0, std::abs(median(model_surface(box)))));
}

TEST(ModelSurface, CylinderSideNormalsAreRadial) {
  const Octree model = test::voxelise(test::cylinder_sdf(0.035, -0.06, 0.12), kCube, 6);
  const ModelSurface s = model_surface(model);
  int side = 0;
  std::vector<double> curvature;
  for (const auto& x : s.samples) {
    if (std::abs(x.position.z()) > 0.06 - 2 * s.radius) continue;
    ++side;
    const Eigen::Vector3d radial(x.position.x(), x.position.y(), 0);
    EXPECT_LT(angle_between_deg(x.normal, radial), 12.0) << x.position.transpose();
    curvature.push_back(x.curvature);
  }
  EXPECT_GT(side, 300);
  // Mean curvature of a cylinder's side: 1/(2r) = 14 /m, convex.
  EXPECT_NEAR(quantile(curvature, 0.5), 1 / 0.07, 0.4 / 0.07);
  EXPECT_GT(quantile(curvature, 0.1), 0.0);
  std::printf("cylinder side curvature: 10%% %.1f, median %.1f, 90%% %.1f /m\n", quantile(curvature, 0.1),
              quantile(curvature, 0.5), quantile(curvature, 0.9));
}

TEST(ModelSurface, LeavesCoarserThanTheMaxDepthAreUncertain) {
  // The upper half resolved to depth 4 only, in a model whose max depth is 6.
  const Octree model =
      test::voxelise(test::sphere_sdf(Eigen::Vector3d::Zero(), 0.05), kCube, 6, [](const Eigen::Vector3d& c) { return c.z() > 0.01 ? 4 : 6; });
  const ModelSurface s = model_surface(model);
  int upper = 0, lower = 0;
  for (const auto& x : s.samples) {
    if (x.position.z() > 0.03) {
      ++upper;
      EXPECT_TRUE(x.uncertain) << x.position.transpose();
    } else if (x.position.z() < -0.01) {
      ++lower;
      EXPECT_FALSE(x.uncertain) << x.position.transpose();
    }
  }
  EXPECT_GT(upper, 10);
  EXPECT_GT(lower, 100);
}

namespace {

// A camera of 320 x 240 pixels, focal length 300, at `eye` looking at the origin.
CameraModel camera_at(const Eigen::Vector3d& eye) {
  return geometry::make_camera(320, 240, 300, 300, 159.5, 119.5, geometry::look_at(eye, Eigen::Vector3d::Zero()));
}

// The rim of a sphere of radius r at the origin seen from `eye`, rendered and outlined as the loop
// does it (a perfect mask).
SilhouetteRim sphere_rim(const Eigen::Vector3d& eye, double r, const Eigen::Vector3d& centre = Eigen::Vector3d::Zero()) {
  auto frame = std::make_shared<Frame>();
  frame->camera = camera_at(eye);
  frame->has_pose = true;
  const auto rendered = geometry::render(geometry::make_uv_sphere(centre, r, 128, 64), frame->camera);
  const auto outline = vision::silhouette_from_mask(rendered.mask, frame);
  EXPECT_TRUE(outline.ok()) << outline.error;
  return outline.ok() ? silhouette_rim(*outline.silhouette) : SilhouetteRim{};
}

// A view whose rim passes through `p` with its cone of sight's normal `cone`, looking at p along
// `sight` (unit): the rim made by hand, one point.
SilhouetteRim rim_through(const Eigen::Vector3d& p, const Eigen::Vector3d& sight, const Eigen::Vector3d& cone) {
  SilhouetteRim rim;
  rim.camera = geometry::make_camera(320, 240, 300, 300, 159.5, 119.5, geometry::look_at(p - 0.3 * sight, p));
  Eigen::Vector2d q;
  EXPECT_TRUE(geometry::project(rim.camera, p, q));
  rim.points.push_back(q);
  rim.normals.push_back(cone.normalized());
  return rim;
}

bool pinned(const SurfaceSample& sample, const std::vector<SilhouetteRim>& views, double tolerance = 0.0025) {
  std::vector<SurfaceSample> s{sample};
  mark_unobserved(s, views, tolerance);
  return !s[0].unpinned;
}

}  // namespace

// The rim's normals are the cone of sight's: each is the normal of a plane through the eye that
// touches the sphere (at distance r from its centre), pointing away from it.
TEST(SilhouetteRim, ASpheresRimNormalsAreItsTangentPlanesThroughTheEye) {
  const double r = 0.05;
  const Eigen::Vector3d eye(0.3, 0.1, 0.2);
  const SilhouetteRim rim = sphere_rim(eye, r);
  ASSERT_GT(rim.points.size(), 200u);
  ASSERT_EQ(rim.normals.size(), rim.points.size());
  const double pixel = eye.norm() / 300;  // a pixel's size at the sphere, metres
  for (const auto& n : rim.normals) {
    EXPECT_NEAR(n.norm(), 1.0, 1e-9);
    EXPECT_NEAR(n.dot(Eigen::Vector3d::Zero() - eye), -r, 1.5 * pixel) << n.transpose();
  }
}

// Where the object leaves the image, the outline runs along the border: that is where the image
// ends, not where the line of sight grazes the object.
TEST(SilhouetteRim, TheImagesBorderIsNotARim) {
  // The sphere's centre 13 cm aside of the line of sight: part of it out of the image.
  auto frame = std::make_shared<Frame>();
  frame->camera = camera_at({0.3, 0, 0});
  frame->has_pose = true;
  const auto rendered = geometry::render(geometry::make_uv_sphere({0, 0.13, 0}, 0.05, 128, 64), frame->camera);
  const auto outline = vision::silhouette_from_mask(rendered.mask, frame);
  ASSERT_TRUE(outline.ok()) << outline.error;
  ASSERT_TRUE(outline.silhouette->touches_border);
  const SilhouetteRim rim = silhouette_rim(*outline.silhouette);
  ASSERT_GT(rim.points.size(), 50u);
  EXPECT_LT(rim.points.size(), outline.silhouette->contour.size() - 50);  // the border's stretch is left out
  for (const auto& q : rim.points) {
    EXPECT_GE(q.x(), 1.5);
    EXPECT_LE(q.x(), 320 - 1 - 1.5);
    EXPECT_GE(q.y(), 1.5);
    EXPECT_LE(q.y(), 240 - 1 - 1.5);
  }
  Silhouette no_frame;
  EXPECT_THROW(silhouette_rim(no_frame), std::invalid_argument);
  no_frame.frame = std::make_shared<Frame>();  // no pose
  EXPECT_THROW(silhouette_rim(no_frame), std::invalid_argument);
  auto distorted = std::make_shared<Frame>();
  distorted->has_pose = true;
  distorted->camera.distortion = (cv::Mat_<double>(1, 4) << 0.1, 0, 0, 0);
  no_frame.frame = distorted;
  EXPECT_THROW(silhouette_rim(no_frame), std::invalid_argument);
}

// Two views of a sphere pin it where their rims cross (where both cones touch it) and nowhere
// else: not on one view's rim alone, not where neither rim passes.
TEST(ModelSurface, ASphereIsPinnedWhereTwoViewsRimsCrossAndNowhereElse) {
  const double r = 0.05, d = 0.3;
  const std::vector<SilhouetteRim> views{sphere_rim({d, 0, 0}, r), sphere_rim({0, d, 0}, r)};
  // The rims are the circles x = r^2/d and y = r^2/d; they cross at z = +-sqrt(r^2 - 2 (r^2/d)^2).
  const double a = r * r / d;
  const std::vector<Eigen::Vector3d> frontier{{a, a, std::sqrt(r * r - 2 * a * a)}, {a, a, -std::sqrt(r * r - 2 * a * a)}};
  auto on_sphere = [&](const Eigen::Vector3d& u) { return SurfaceSample{r * u.normalized(), u.normalized()}; };
  for (const auto& f : frontier) EXPECT_TRUE(pinned(on_sphere(f), views)) << f.transpose();
  // On the first view's rim only, half way round from the crossings; and facing both views.
  EXPECT_FALSE(pinned(on_sphere({a, -std::sqrt(r * r - a * a), 0}), views));
  EXPECT_FALSE(pinned(on_sphere({1, 1, 0}), views));
  // Every pinned sample of the sphere lies near a crossing.
  int pinned_count = 0;
  for (int i = 0; i < 2000; ++i) {
    const double z = 1 - 2 * (i + 0.5) / 2000, phi = i * 2.399963229728653;  // a Fibonacci sphere
    const Eigen::Vector3d u(std::sqrt(1 - z * z) * std::cos(phi), std::sqrt(1 - z * z) * std::sin(phi), z);
    if (!pinned(on_sphere(u), views)) continue;
    ++pinned_count;
    double nearest = 180;
    for (const auto& f : frontier) nearest = std::min(nearest, angle_between_deg(u, f));
    EXPECT_LT(nearest, 25.0) << u.transpose();
  }
  EXPECT_GT(pinned_count, 4);
  EXPECT_LT(pinned_count, 200);  // of 2000
}

// Two cones of sight also cross along an edge of the carved model, away from the object. There the
// model's fitted normal lies between the two cones' and both lines of sight graze it; the cones'
// tangent planes meet at an angle, which tells the edge from a point both cones touch.
TEST(ModelSurface, TwoConesCrossingAtAnEdgeOfTheModelDoNotPinIt) {
  const double k = 20 * std::numbers::pi / 180;
  const SurfaceSample edge{{0.01, 0.02, 0.03}, {0, 0, 1}};  // the crease runs along y; the fit's normal +z between its faces
  const Eigen::Vector3d face_a(std::sin(k), 0, std::cos(k)), face_b(-std::sin(k), 0, std::cos(k));
  // Each line of sight in its cone's plane, 45 degrees from the crease: 83 degrees apart, each 14
  // degrees from the fitted tangent plane.
  const Eigen::Vector3d y = Eigen::Vector3d::UnitY();
  const Eigen::Vector3d sight_a = (y + Eigen::Vector3d(std::cos(k), 0, -std::sin(k))).normalized();
  const Eigen::Vector3d sight_b = (y - Eigen::Vector3d(std::cos(k), 0, std::sin(k))).normalized();
  ASSERT_LT(std::abs(sight_a.dot(edge.normal)), std::sin(15 * std::numbers::pi / 180));
  ASSERT_LT(std::abs(sight_b.dot(edge.normal)), std::sin(15 * std::numbers::pi / 180));
  EXPECT_FALSE(pinned(edge, {rim_through(edge.position, sight_a, face_a), rim_through(edge.position, sight_b, face_b)}));
  // The same lines of sight with cones tangent to one surface there: pinned.
  const Eigen::Vector3d sa = (y + Eigen::Vector3d::UnitX()).normalized(), sb = (y - Eigen::Vector3d::UnitX()).normalized();
  EXPECT_TRUE(pinned(edge, {rim_through(edge.position, sa, edge.normal), rim_through(edge.position, sb, edge.normal)}));
  // One rim, or two along the same line of sight: a tangent line, not a point.
  EXPECT_FALSE(pinned(edge, {rim_through(edge.position, sa, edge.normal)}));
  EXPECT_FALSE(pinned(edge, {rim_through(edge.position, sa, edge.normal), rim_through(edge.position, -sa, edge.normal)}));
  // A line of sight that does not graze the sample's tangent plane: the rim is elsewhere.
  const Eigen::Vector3d steep = (y + Eigen::Vector3d(0, 0, -1)).normalized();
  EXPECT_FALSE(pinned(edge, {rim_through(edge.position, sa, edge.normal), rim_through(edge.position, steep, edge.normal)}));
  // A rim that passes 2 cm away from the sample in the image's plane: not through it.
  const SilhouetteRim far = rim_through(edge.position + Eigen::Vector3d(0, 0, 0.02), sb, edge.normal);
  EXPECT_FALSE(pinned(edge, {rim_through(edge.position, sa, edge.normal), far}));
  EXPECT_TRUE(pinned(edge, {rim_through(edge.position, sa, edge.normal), far}, 0.025));  // within a 2.5 cm tolerance
  // A sample almost in a camera's plane projects 10^12 pixels off its image: no rim there.
  const SilhouetteRim v = rim_through(edge.position, sa, edge.normal);
  const Eigen::Vector3d across = sa.cross(edge.normal).normalized();
  const SurfaceSample at_eye{v.camera.centre_in_world() + 1e-12 * sa + 0.01 * across, edge.normal};
  EXPECT_FALSE(pinned(at_eye, {v, rim_through(edge.position, sb, edge.normal)}));
  std::vector<SurfaceSample> s{edge};
  EXPECT_THROW(mark_unobserved(s, std::vector<SilhouetteRim>{}, 0.0025, 0.0), std::invalid_argument);
  EXPECT_THROW(mark_unobserved(s, std::vector<SilhouetteRim>{}, -1.0), std::invalid_argument);
}

// Carving keeps what no view saw: here a block above the object that no view had in its image,
// and the silhouettes' cone under the table (the object box reaches down to z = -0.02). On a
// table at z = 0, the object is what rests on it, above it.
TEST(ModelSurface, OnATableTheObjectIsWhatRestsOnIt) {
  const Eigen::AlignedBox3d workspace(Eigen::Vector3d(-0.1, -0.1, -0.02), Eigen::Vector3d(0.1, 0.1, 0.18));
  const test::Sdf object = test::box_sdf({0, 0, 0.02}, {0.06, 0.06, 0.08});  // z -0.02 .. 0.06
  const test::Sdf above = test::box_sdf({0, 0, 0.14}, {0.08, 0.08, 0.04});   // z 0.12 .. 0.16
  const Octree model = test::voxelise([&](const Eigen::Vector3d& p) { return std::min(object(p), above(p)); }, workspace, 6);
  auto count = [](const ModelSurface& s, auto&& where) {
    return std::count_if(s.samples.begin(), s.samples.end(), [&](const SurfaceSample& x) { return where(x.position.z()); });
  };
  const ModelSurface all = model_surface(model);
  EXPECT_EQ(all.unsupported_leaves, 0u);
  EXPECT_GT(count(all, [](double z) { return z > 0.11; }), 100);
  EXPECT_GT(count(all, [](double z) { return z < -0.005; }), 50);

  ModelSurfaceParams params;
  params.table_z = 0.0;
  const ModelSurface s = model_surface(model, params);
  EXPECT_GT(s.unsupported_leaves, 0u);  // the block above: nothing joins it to the table
  EXPECT_EQ(s.leaves, all.leaves);
  EXPECT_GT(count(s, [](double z) { return z > 0.055; }), 100);  // the object's top face
  EXPECT_EQ(count(s, [](double z) { return z > 0.07; }), 0);
  EXPECT_EQ(count(s, [](double z) { return z < 0.0; }), 0);
  // The object's sides are as without the table.
  EXPECT_EQ(count(s, [](double z) { return z > 0.01 && z < 0.05; }), count(all, [](double z) { return z > 0.01 && z < 0.05; }));
}

// A sphere touches the table at one point. A leaf is occupied when its centre is inside (the
// carver's leaf test): the leaves that straddle the table under the contact have their centres
// below the sphere, so none of the model reaches down to the table; its lowest leaves stand a
// fraction of an edge above it. The sphere is the object still; a block floating over it, cut off
// by carved space, is not, nor one that floats a few leaves above the table.
TEST(ModelSurface, AnObjectTouchingTheTableAtAPointIsTheObjectAndWhatFloatsIsNot) {
  const Eigen::AlignedBox3d workspace(Eigen::Vector3d(-0.13, -0.13, -0.02), Eigen::Vector3d(0.13, 0.13, 0.24));  // the grasp task's
  const double r = 0.03;
  const test::Sdf sphere = test::sphere_sdf({0, 0, r}, r);
  const test::Sdf above = test::box_sdf({0, 0, 0.16}, {0.08, 0.08, 0.04});
  const test::Sdf beside = test::box_sdf({0.08, 0, 0.03}, {0.02, 0.02, 0.02});  // z 0.02 .. 0.04, five leaves up
  const Octree model = test::voxelise([&](const Eigen::Vector3d& p) { return std::min({sphere(p), above(p), beside(p)}); }, workspace, 6);
  double lowest = INFINITY;
  model.for_each_occupied_leaf([&](const OctreeCell& c) { lowest = std::min(lowest, c.centre.z() - c.half_size); });
  ASSERT_GT(lowest, 0.0);  // nothing reaches down to the table
  ASSERT_LT(lowest, workspace.sizes().x() / 64);

  ModelSurfaceParams params;
  params.table_z = 0.0;
  const ModelSurface s = model_surface(model, params);
  ASSERT_FALSE(s.samples.empty());
  Eigen::AlignedBox3d kept;
  for (const auto& x : s.samples) kept.extend(x.position);
  EXPECT_GT(kept.max().z(), 2 * r - 0.004);  // the sphere's top
  EXPECT_LT(kept.max().z(), 2 * r + 0.004);  // and not the block above it
  EXPECT_LT(kept.max().x(), r + 0.004);      // nor the block beside it
  EXPECT_LT(kept.min().z(), 0.004);          // down to its lowest point
  EXPECT_GT(s.unsupported_leaves, 0u);
}

// A model in kCube whose root is its only leaf.
Octree root_only(NodeState state, int max_depth) {
  Octree t;
  t.bounds = kCube;
  t.max_depth = max_depth;
  t.root.set_state(state);
  return t;
}

TEST(ModelSurface, AnEmptyModelHasNoSurface) {
  const ModelSurface s = model_surface(root_only(NodeState::Empty, 6));
  EXPECT_TRUE(s.samples.empty());
  EXPECT_EQ(s.leaves, 0u);
  Octree none;  // no tree yet
  none.node_count = 0;
  EXPECT_TRUE(model_surface(none).samples.empty());
}

TEST(ModelSurface, AFullRootIsOneBlock) {
  const ModelSurface s = model_surface(root_only(NodeState::Full, 0));
  ASSERT_EQ(s.samples.size(), 1u);
  EXPECT_NEAR(s.samples[0].normal.norm(), 1.0, 1e-12);
}

TEST(ModelSurface, ARootBoxThatIsNotACubeIsAClearError) {
  Octree t;
  t.bounds = Eigen::AlignedBox3d(Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 1, 2));
  try {
    model_surface(t);
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("must be a cube"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace fba::grasp
