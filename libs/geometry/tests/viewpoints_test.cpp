#include <cmath>
#include <limits>
#include <numbers>

#include <gtest/gtest.h>

#include "fba/geometry/viewpoints.hpp"

namespace fba::geometry {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

void expect_looks_at(const Eigen::Isometry3d& pose, const Eigen::Vector3d& target, double radius) {
  const CameraModel cam = make_camera(640, 480, 600, 600, 319.5, 239.5, pose);
  // A proper rotation.
  EXPECT_TRUE((pose.linear() * pose.linear().transpose()).isIdentity(1e-12));
  EXPECT_NEAR(pose.linear().determinant(), 1.0, 1e-12);
  // The target projects onto the principal point, in front of the camera, at `radius`.
  Eigen::Vector2d px;
  ASSERT_TRUE(project(cam, target, px));
  EXPECT_NEAR(px.x(), 319.5, 1e-9);
  EXPECT_NEAR(px.y(), 239.5, 1e-9);
  EXPECT_NEAR((pose * target).z(), radius, 1e-9);
  EXPECT_NEAR((cam.centre_in_world() - target).norm(), radius, 1e-9);
  // World up appears as image up (smaller v) unless looking straight down.
  const Eigen::Vector3d above = target + Eigen::Vector3d(0, 0, 0.01);
  Eigen::Vector2d px_above;
  ASSERT_TRUE(project(cam, above, px_above));
  const Eigen::Vector3d forward = pose.linear().row(2).transpose();
  if (std::abs(forward.z()) < 0.99) {
    EXPECT_LT(px_above.y(), px.y());
    EXPECT_NEAR(px_above.x(), px.x(), 1e-9) << "no roll: vertical stays vertical";
  }
}

TEST(Viewpoints, RingPosesLookAtTargetAtGivenElevationAndEvenAzimuths) {
  const Eigen::Vector3d target(0.1, -0.05, 0.04);
  const double elevation = 30 * kDeg, radius = 0.5;
  const auto poses = ring_views(7, elevation, radius, target, 0.3);
  ASSERT_EQ(poses.size(), 7u);
  for (std::size_t i = 0; i < poses.size(); ++i) {
    expect_looks_at(poses[i], target, radius);
    const Eigen::Vector3d d = poses[i].inverse().translation() - target;
    EXPECT_NEAR(std::asin(d.z() / d.norm()), elevation, 1e-9);
    const double azimuth = std::atan2(d.y(), d.x());
    const double expected = 0.3 + 2 * std::numbers::pi * i / 7;
    EXPECT_NEAR(std::remainder(azimuth - expected, 2 * std::numbers::pi), 0.0, 1e-9);
  }
}

TEST(Viewpoints, StraightDownViewIsWellDefined) {
  const Eigen::Isometry3d pose = look_at({0, 0, 1}, {0, 0, 0});
  expect_looks_at(pose, Eigen::Vector3d::Zero(), 1.0);
  EXPECT_TRUE(pose.matrix().allFinite());
}

TEST(Viewpoints, HemisphereViewsLookAtTargetWithinElevationBand) {
  const Eigen::Vector3d target(0, 0, 0.05);
  const auto poses = hemisphere_views(40, 10 * kDeg, 80 * kDeg, 0.6, target);
  ASSERT_EQ(poses.size(), 40u);
  for (const auto& pose : poses) {
    expect_looks_at(pose, target, 0.6);
    const Eigen::Vector3d d = pose.inverse().translation() - target;
    const double elevation = std::asin(d.z() / d.norm());
    EXPECT_GE(elevation, 10 * kDeg - 1e-9);
    EXPECT_LE(elevation, 80 * kDeg + 1e-9);
  }
}

TEST(Viewpoints, HemisphereViewsAreEvenlySpread) {
  const int n = 200;
  const auto poses = hemisphere_views(n, 0.0, std::numbers::pi / 2, 1.0);
  std::vector<Eigen::Vector3d> dirs;
  for (const auto& p : poses) dirs.push_back(p.inverse().translation().normalized());
  // Equal area: as many views above the height 0.5 as below it (the two bands have equal area).
  int upper = 0;
  for (const auto& d : dirs) upper += d.z() > 0.5;
  EXPECT_NEAR(upper, n / 2, 2);
  // No clumps and no holes: every nearest-neighbour angle is within a factor of the ideal
  // spacing sqrt(area / n) of a hemisphere (area 2 pi).
  const double ideal = std::sqrt(2 * std::numbers::pi / n);
  double min_nn = std::numeric_limits<double>::max(), max_nn = 0;
  for (std::size_t i = 0; i < dirs.size(); ++i) {
    double nn = std::numeric_limits<double>::max();
    for (std::size_t j = 0; j < dirs.size(); ++j)
      if (i != j) nn = std::min(nn, std::acos(std::clamp(dirs[i].dot(dirs[j]), -1.0, 1.0)));
    min_nn = std::min(min_nn, nn);
    max_nn = std::max(max_nn, nn);
  }
  EXPECT_GT(min_nn, 0.5 * ideal);
  EXPECT_LT(max_nn, 1.5 * ideal);
  // The mean direction of an even spread over the hemisphere points straight up.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& d : dirs) mean += d / n;
  EXPECT_LT(mean.head<2>().norm(), 0.02);
  EXPECT_NEAR(mean.z(), 0.5, 0.02);  // the hemisphere's mean height
}

TEST(Viewpoints, MakeCameraFillsIntrinsics) {
  const CameraModel c = make_camera(640, 480, 600, 610, 320, 240);
  EXPECT_EQ(c.width, 640);
  EXPECT_EQ(c.height, 480);
  EXPECT_EQ(c.K(0, 0), 600);
  EXPECT_EQ(c.K(1, 1), 610);
  EXPECT_EQ(c.K(0, 2), 320);
  EXPECT_EQ(c.K(1, 2), 240);
  EXPECT_EQ(c.K(2, 2), 1);
  EXPECT_EQ(c.K(0, 1), 0);
  EXPECT_TRUE(c.distortion.empty());
}

TEST(Viewpoints, RejectsBadArguments) {
  EXPECT_THROW(look_at({1, 2, 3}, {1, 2, 3}), std::invalid_argument);
  EXPECT_THROW(ring_views(4, 0.3, 0.0), std::invalid_argument);
  EXPECT_THROW(hemisphere_views(4, 1.0, 0.5, 1.0), std::invalid_argument);
}

}  // namespace
}  // namespace fba::geometry
