#include "fba/geometry/viewpoints.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace fba::geometry {

Eigen::Isometry3d look_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                          const Eigen::Vector3d& up) {
  const Eigen::Vector3d forward_raw = target - eye;
  if (forward_raw.norm() <= 0) throw std::invalid_argument("look_at: eye equals target");
  const Eigen::Vector3d z = forward_raw.normalized();
  Eigen::Vector3d x = z.cross(up);  // right = forward x up (e.g. looking along +x, right is -y)
  if (x.norm() < 1e-9) {
    // Looking along up: any right vector is as good; take one orthogonal to z.
    x = z.cross(Eigen::Vector3d::UnitY());
    if (x.norm() < 1e-9) x = z.cross(Eigen::Vector3d::UnitX());
  }
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);  // down
  Eigen::Matrix3d world_from_cam_R;
  world_from_cam_R.col(0) = x;
  world_from_cam_R.col(1) = y;
  world_from_cam_R.col(2) = z;
  Eigen::Isometry3d camera_from_world = Eigen::Isometry3d::Identity();
  camera_from_world.linear() = world_from_cam_R.transpose();
  camera_from_world.translation() = -world_from_cam_R.transpose() * eye;
  return camera_from_world;
}

Eigen::Vector3d spherical_eye(const Eigen::Vector3d& target, double radius, double azimuth,
                              double elevation) {
  return target + radius * Eigen::Vector3d(std::cos(elevation) * std::cos(azimuth),
                                           std::cos(elevation) * std::sin(azimuth),
                                           std::sin(elevation));
}

std::vector<Eigen::Isometry3d> ring_views(int n, double elevation, double radius,
                                          const Eigen::Vector3d& target, double azimuth_offset) {
  if (n < 0 || radius <= 0) throw std::invalid_argument("ring_views: need n >= 0 and radius > 0");
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; i < n; ++i) {
    const double azimuth = azimuth_offset + 2 * std::numbers::pi * i / n;
    poses.push_back(look_at(spherical_eye(target, radius, azimuth, elevation), target));
  }
  return poses;
}

std::vector<Eigen::Isometry3d> hemisphere_views(int n, double min_elevation, double max_elevation,
                                                double radius, const Eigen::Vector3d& target) {
  if (n < 0 || radius <= 0 || min_elevation > max_elevation)
    throw std::invalid_argument(
        "hemisphere_views: need n >= 0, radius > 0, min_elevation <= max_elevation");
  // Area on a sphere is uniform in height (Archimedes), so equal steps of sin(elevation) give
  // equal-area bands; the golden angle keeps successive azimuths apart for any n.
  const double golden_angle = std::numbers::pi * (3.0 - std::sqrt(5.0));
  const double h0 = std::sin(min_elevation), h1 = std::sin(max_elevation);
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; i < n; ++i) {
    const double h = h0 + (h1 - h0) * (i + 0.5) / n;
    const double elevation = std::asin(std::clamp(h, -1.0, 1.0));
    const double azimuth = golden_angle * i;
    poses.push_back(look_at(spherical_eye(target, radius, azimuth, elevation), target));
  }
  return poses;
}

CameraModel make_camera(int width, int height, double fx, double fy, double cx, double cy,
                        const Eigen::Isometry3d& camera_from_world) {
  CameraModel c;
  c.width = width;
  c.height = height;
  c.K << fx, 0, cx, 0, fy, cy, 0, 0, 1;
  c.camera_from_world = camera_from_world;
  return c;
}

bool project(const CameraModel& camera, const Eigen::Vector3d& world, Eigen::Vector2d& pixel) {
  const Eigen::Vector3d p = camera.camera_from_world * world;
  if (p.z() <= 0) return false;
  const Eigen::Vector3d h = camera.K * p;
  pixel = h.head<2>() / h.z();
  return true;
}

double framing_distance(const Eigen::AlignedBox3d& box, int width, int height, double focal, double margin) {
  const double sphere_radius = box.sizes().norm() / 2;
  const double half_fov = std::atan(std::min(width, height) / 2.0 / focal);
  return margin * sphere_radius / std::sin(half_fov);
}

CameraModel framing_camera(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& centre,
                           const Eigen::Vector3d& toward, const Eigen::Vector3d& up, int width, int height, double fill) {
  const int W = width, H = height;
  const double f = W;
  double radius = 1e-6;
  for (const auto& p : points) radius = std::max(radius, (p - centre).norm());
  // A projection shrinks about as 1 / distance: a few steps settle the distance.
  double d = framing_distance(Eigen::AlignedBox3d(centre, centre + Eigen::Vector3d::Constant(radius)), W, H, f);
  for (int i = 0; i < 8; ++i) {
    const CameraModel camera = make_camera(W, H, f, f, (W - 1) / 2.0, (H - 1) / 2.0, look_at(centre + d * toward, centre, up));
    double filled = 0;
    for (const auto& p : points) {
      Eigen::Vector2d px;
      if (!project(camera, p, px)) filled = 10;
      else filled = std::max({filled, std::abs(px.x() - camera.K(0, 2)) / (W / 2.0), std::abs(px.y() - camera.K(1, 2)) / (H / 2.0)});
    }
    d = std::max(d * filled / fill, 1.05 * radius);
  }
  return make_camera(W, H, f, f, (W - 1) / 2.0, (H - 1) / 2.0, look_at(centre + d * toward, centre, up));
}

}  // namespace fba::geometry
