#include <cmath>
#include <numbers>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "fba/geometry/mesh_io.hpp"
#include "fba/geometry/renderer.hpp"
#include "fba/geometry/viewpoints.hpp"
#include "support/geometry_checks.hpp"

namespace fba::geometry {
namespace {

constexpr double kF = 600, kCx = 320, kCy = 240;

CameraModel camera_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target) {
  return make_camera(640, 480, kF, kF, kCx, kCy, look_at(eye, target));
}

TEST(Renderer, SphereMaskAreaMatchesAnalyticProjection) {
  const double r = 0.1, d = 0.5;
  const TriangleMesh sphere = make_uv_sphere({0, 0, 0}, r, 256, 128);
  const auto cam = camera_at({d, 0, 0}, {0, 0, 0});
  const RenderResult out = render(sphere, cam);
  // A sphere centred on the optical axis projects to a disc of radius f * r / sqrt(d^2 - r^2).
  const double radius_px = kF * r / std::sqrt(d * d - r * r);
  const double expected = std::numbers::pi * radius_px * radius_px;
  const double area = cv::countNonZero(out.mask);
  EXPECT_NEAR(area / expected, 1.0, 0.01) << area << " vs " << expected;
}

TEST(Renderer, CubeMaskIsTheFrontFaceSquareAndDepthIsExact) {
  const double s = 0.1, d = 0.4;  // cube side, camera distance to the cube centre
  const TriangleMesh cube = make_box(Eigen::Vector3d::Constant(-s / 2), Eigen::Vector3d::Constant(s / 2));
  const auto cam = camera_at({0, -d, 0}, {0, 0, 0});
  const RenderResult out = render(cube, cam);
  // Seen head-on, the silhouette is the near face: a square of side f * s / (d - s/2).
  const double side_px = kF * s / (d - s / 2);
  const double area = cv::countNonZero(out.mask);
  EXPECT_NEAR(area / (side_px * side_px), 1.0, 0.01) << area;
  EXPECT_NEAR(out.depth.at<float>(static_cast<int>(kCy), static_cast<int>(kCx)), d - s / 2, 1e-5);
  // A corner pixel of the face: the face is planar and frontal, so depth is the same there.
  EXPECT_NEAR(out.depth.at<float>(static_cast<int>(kCy + side_px / 2 - 2),
                                  static_cast<int>(kCx - side_px / 2 + 2)),
              d - s / 2, 1e-5);
}

TEST(Renderer, SphereDepthAtCentreIsDistanceToNearestPoint) {
  const double r = 0.08, d = 0.6;
  // The camera looks down the z axis, where the UV sphere has a vertex (the pole).
  const TriangleMesh sphere = make_uv_sphere({0, 0, 0}, r, 64, 32);
  const auto cam = camera_at({0, 0, d}, {0, 0, 0});
  const RenderResult out = render(sphere, cam);
  EXPECT_NEAR(out.depth.at<float>(240, 320), d - r, 1e-5);
  EXPECT_EQ(out.mask.at<uchar>(240, 320), 255);
  EXPECT_EQ(out.depth.at<float>(0, 0), 0.0f) << "0 where empty";
}

TEST(Renderer, DepthIsPerspectiveCorrectOnATiltedPlane) {
  // One big triangle in the plane z = 0.2 * x, seen from above: depth along each pixel ray is
  // known in closed form; linear interpolation of z in screen space would be off by centimetres.
  TriangleMesh plane;
  plane.vertices = {Eigen::Vector3f(-1.f, -1.f, -0.2f), Eigen::Vector3f(1.f, -1.f, 0.2f),
                    Eigen::Vector3f(0.f, 2.f, 0.0f)};
  plane.triangles = {Eigen::Vector3i(0, 1, 2)};
  const double h = 0.5;
  const auto cam = camera_at({0, 0, h}, {0, 0, 0});
  const RenderResult out = render(plane, cam);
  const Eigen::Matrix3d Kinv = cam.K.inverse();
  const Eigen::Isometry3d world_from_cam = cam.camera_from_world.inverse();
  int checked = 0;
  for (int v = 20; v < 480; v += 60)
    for (int u = 20; u < 640; u += 60) {
      if (!out.mask.at<uchar>(v, u)) continue;
      // Ray with camera z = 1: point = c + s * dir, and s is the camera depth.
      const Eigen::Vector3d dir = world_from_cam.linear() * (Kinv * Eigen::Vector3d(u, v, 1));
      const Eigen::Vector3d c = world_from_cam.translation();
      const double s = (0.2 * c.x() - c.z()) / (dir.z() - 0.2 * dir.x());
      EXPECT_NEAR(out.depth.at<float>(v, u), s, 1e-5) << u << "," << v;
      ++checked;
    }
  EXPECT_GT(checked, 30);
}

TEST(Renderer, GeometryBehindTheCameraIsClippedNotWrapped) {
  // A floor quad z = 0 reaching far behind a camera 0.3 above it, looking level along +y.
  TriangleMesh floor = make_box({-5, -5, -0.01}, {5, 5, 0});
  const Eigen::Vector3d eye(0, 0, 0.3);
  const auto cam = make_camera(640, 480, kF, kF, kCx, kCy, look_at(eye, eye + Eigen::Vector3d(0, 1, 0)));
  const RenderResult out = render(floor, cam);
  // Above the horizon (v < cy) there is nothing; below it the floor is at depth h f / (v - cy)
  // until the floor's far edge.
  EXPECT_EQ(cv::countNonZero(out.mask.rowRange(0, 239)), 0);
  for (int v : {300, 360, 479}) {
    EXPECT_EQ(out.mask.at<uchar>(v, 320), 255);
    EXPECT_NEAR(out.depth.at<float>(v, 320), 0.3 * kF / (v - kCy), 1e-4) << v;
  }
  const cv::Mat d = out.depth;
  double lo, hi;
  cv::minMaxLoc(d, &lo, &hi, nullptr, nullptr, out.mask);
  EXPECT_GE(lo, 1e-3) << "nothing nearer than the near plane";
}

TEST(Renderer, MaskMatchesDepthAndShadingDependsOnLight) {
  const TriangleMesh sphere = make_uv_sphere({0, 0, 0}, 0.1, 64, 32);
  const auto cam = camera_at({0.5, 0, 0.2}, {0, 0, 0});
  RenderOptions opt;
  const RenderResult a = render(sphere, cam, opt);
  cv::Mat has_depth = a.depth > 0;
  EXPECT_EQ(cv::countNonZero(has_depth != a.mask), 0);
  // Headlight: the centre faces the light and is brighter than the rim.
  const cv::Vec3b centre = a.colour.at<cv::Vec3b>(240, 320);
  EXPECT_EQ(a.mask.at<uchar>(240, 320), 255);
  EXPECT_GT(centre[2], 200);
  // A light from behind the object leaves the visible side at ambient.
  opt.light_towards_world = Eigen::Vector3d(-1, 0, -0.4);
  const RenderResult b = render(sphere, cam, opt);
  const cv::Vec3b dark = b.colour.at<cv::Vec3b>(240, 320);
  EXPECT_NEAR(dark[2], opt.object_colour[2] * opt.ambient, 1.0);
  EXPECT_EQ(cv::countNonZero(a.mask != b.mask), 0) << "lighting does not change coverage";
}

TEST(Renderer, TableHidesWhatIsBelowIt) {
  const TriangleMesh sphere = make_uv_sphere({0, 0, 0}, 0.1, 64, 32);
  const auto cam = camera_at({0.4, 0.1, 0.3}, {0, 0, 0});
  RenderOptions opt;
  const RenderResult free = render(sphere, cam, opt);
  opt.table = true;
  opt.table_z = 0.0;
  const RenderResult on_table = render(sphere, cam, opt);
  const int a = cv::countNonZero(free.mask), b = cv::countNonZero(on_table.mask);
  EXPECT_LT(b, a);
  EXPECT_GT(b, a / 2) << "the upper half and more is visible from above";
  // Every pixel left in the mask back-projects to a point on or above the table.
  const Eigen::Matrix3d Kinv = cam.K.inverse();
  const Eigen::Isometry3d wfc = cam.camera_from_world.inverse();
  for (int v = 0; v < 480; v += 3)
    for (int u = 0; u < 640; u += 3)
      if (on_table.mask.at<uchar>(v, u)) {
        const Eigen::Vector3d p =
            wfc * (on_table.depth.at<float>(v, u) * (Kinv * Eigen::Vector3d(u, v, 1)));
        ASSERT_GE(p.z(), -1e-4);
      }
  // The table is drawn: the background corner differs from the table-less render.
  EXPECT_NE(free.colour.at<cv::Vec3b>(479, 0), on_table.colour.at<cv::Vec3b>(479, 0));
}

// Two boxes in colours of their own, one partly in front of the other, rendered apart and
// composited: in either order the same picture, whose depth and mask are the two rendered as one
// mesh, the nearer box's colour where they overlap, and the background where neither is.
TEST(Renderer, CompositedPartsHideOneAnotherByDepthInEitherOrder) {
  const TriangleMesh near_box = make_box({-0.05, -0.15, -0.05}, {0.05, -0.05, 0.05});
  const TriangleMesh far_box = make_box({0.0, 0.0, -0.08}, {0.16, 0.1, 0.08});
  const auto cam = camera_at({0, -0.6, 0}, {0, 0, 0});
  RenderOptions red, blue;
  red.object_colour = {0, 0, 255};
  blue.object_colour = {255, 0, 0};
  const RenderResult a = render(near_box, cam, red), b = render(far_box, cam, blue);
  RenderResult ab{a.colour.clone(), a.depth.clone(), a.mask.clone()};
  composite(ab, b);
  RenderResult ba{b.colour.clone(), b.depth.clone(), b.mask.clone()};
  composite(ba, a);
  TriangleMesh both = near_box;
  for (const auto& v : far_box.vertices) both.vertices.push_back(v);
  for (const auto& t : far_box.triangles) both.triangles.push_back(t + Eigen::Vector3i::Constant(int(near_box.vertices.size())));
  const RenderResult one = render(both, cam, red);

  EXPECT_EQ(cv::countNonZero(ab.colour.reshape(1) != ba.colour.reshape(1)), 0);
  EXPECT_EQ(cv::countNonZero(ab.depth != one.depth), 0);
  EXPECT_EQ(cv::countNonZero(ab.mask != one.mask), 0);
  EXPECT_EQ(cv::countNonZero(ba.depth != one.depth), 0);
  // Each box alone covers pixels the other covers too, so the overlap is tested.
  cv::Mat overlap = a.mask & b.mask;
  ASSERT_GT(cv::countNonZero(overlap), 1000);
  for (int v = 0; v < 480; ++v)
    for (int u = 0; u < 640; ++u) {
      const cv::Vec3b c = ab.colour.at<cv::Vec3b>(v, u);
      if (overlap.at<uchar>(v, u)) {
        ASSERT_EQ(c, a.colour.at<cv::Vec3b>(v, u)) << "the near box hides the far one at " << u << ", " << v;
      } else if (b.mask.at<uchar>(v, u)) {
        ASSERT_EQ(c, b.colour.at<cv::Vec3b>(v, u)) << u << ", " << v;
      } else if (!a.mask.at<uchar>(v, u)) {
        ASSERT_EQ(c, a.colour.at<cv::Vec3b>(v, u)) << "background at " << u << ", " << v;
      }
    }
  RenderResult other_size{cv::Mat(10, 10, CV_8UC3), cv::Mat(10, 10, CV_32FC1), cv::Mat(10, 10, CV_8UC1)};
  EXPECT_THROW(composite(ab, other_size), std::invalid_argument);
}

TEST(Renderer, NoiseIsSeededAndRepeatable) {
  const TriangleMesh sphere = make_uv_sphere({0, 0, 0}, 0.1, 32, 16);
  const auto cam = camera_at({0.5, 0, 0.2}, {0, 0, 0});
  RenderOptions opt;
  const RenderResult clean = render(sphere, cam, opt);
  opt.noise_sigma = 5.0;
  opt.seed = 42;
  const RenderResult a = render(sphere, cam, opt), b = render(sphere, cam, opt);
  opt.seed = 43;
  const RenderResult c = render(sphere, cam, opt);
  EXPECT_EQ(cv::norm(a.colour, b.colour, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(a.colour, c.colour, cv::NORM_L1), 0.0);
  // The noise has about the requested spread (measured where the clean image is mid-grey, so
  // clipping at 0 / 255 does not bias it) and leaves mask and depth alone.
  cv::Mat diff;
  cv::Mat(a.colour).convertTo(diff, CV_32FC3);
  cv::Mat clean_f;
  clean.colour.convertTo(clean_f, CV_32FC3);
  diff -= clean_f;
  cv::Scalar mean, stddev;
  cv::meanStdDev(diff.reshape(1), mean, stddev);
  EXPECT_NEAR(stddev[0], 5.0, 0.5);
  EXPECT_EQ(cv::countNonZero(a.mask != clean.mask), 0);
  EXPECT_EQ(cv::norm(a.depth, clean.depth, cv::NORM_INF), 0.0);
}

// Its speed is measured in renderer_benchmark.cpp (a test asserts no time: the machine is shared).
TEST(Renderer, YcbMeshAt640x480CoversItsProjection) {
  const TriangleMesh mesh = load_mesh(test::ycb_mesh("YcbMustardBottle"));
  const auto box = mesh_bounds(mesh);
  const auto cam = camera_at(box.center() + Eigen::Vector3d(0.35, 0.1, 0.2), box.center());
  const RenderResult out = render(mesh, cam);
  EXPECT_GT(cv::countNonZero(out.mask), 5000);
}

}  // namespace
}  // namespace fba::geometry
