// Camera poses around a target, and pinhole camera construction.
//
// Conventions: the world is z-up; cameras follow OpenCV (x right, y down, z forward); poses are
// camera_from_world (x_cam = R * x_world + t), as fba::CameraModel stores them. Angles in radians.
#pragma once

#include <vector>

#include <Eigen/Geometry>

#include "fba/types/camera.hpp"

namespace fba::geometry {

// A camera at `eye` looking at `target`, its image "up" (-y) as close to `up` as possible.
// When the viewing direction is parallel to `up` (e.g. straight down), the world y axis (or x)
// is used instead so the pose is always defined. eye must differ from target.
Eigen::Isometry3d look_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                          const Eigen::Vector3d& up = Eigen::Vector3d::UnitZ());

// Camera centre for a view at `azimuth` (from the world x axis towards y) and `elevation` (above
// the target's horizontal plane) at distance `radius` from `target`.
Eigen::Vector3d spherical_eye(const Eigen::Vector3d& target, double radius, double azimuth,
                              double elevation);

// n views evenly spaced in azimuth (starting at azimuth_offset) at one elevation.
std::vector<Eigen::Isometry3d> ring_views(int n, double elevation, double radius,
                                          const Eigen::Vector3d& target = Eigen::Vector3d::Zero(),
                                          double azimuth_offset = 0.0);

// n views spread evenly (equal area per view) over the band of the upper sphere between
// min_elevation and max_elevation, by a Fibonacci spiral: heights sin(elevation) uniform in the
// band, azimuths advancing by the golden angle. min 0, max pi/2 covers the whole hemisphere.
std::vector<Eigen::Isometry3d> hemisphere_views(int n, double min_elevation, double max_elevation,
                                                double radius,
                                                const Eigen::Vector3d& target = Eigen::Vector3d::Zero());

// How far from the box's centre a camera of this size and focal length must stand for the
// sphere around the box to fit the image's shorter side, with `margin` to spare (1.05: 5%).
double framing_distance(const Eigen::AlignedBox3d& box, int width, int height, double focal, double margin = 1.05);

// A picture's camera, width x height pixels with the width as focal length, looking at `centre`
// from along the unit vector `toward`, its image up as near `up` as look_at makes it, and as near
// as frames `points`: from the distance that fits their sphere about `centre`, nearer until their
// projections fill the share `fill` of the picture's half-width or half-height.
CameraModel framing_camera(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& centre,
                           const Eigen::Vector3d& toward, const Eigen::Vector3d& up, int width, int height, double fill);

// An ideal pinhole camera (no distortion) with the given intrinsics and pose.
CameraModel make_camera(int width, int height, double fx, double fy, double cx, double cy,
                        const Eigen::Isometry3d& camera_from_world = Eigen::Isometry3d::Identity());

// Projects a world point to pixel coordinates (OpenCV: pixel (u, v) has its centre at (u, v)).
// Ignores distortion. Returns false for a point at or behind the camera plane.
bool project(const CameraModel& camera, const Eigen::Vector3d& world, Eigen::Vector2d& pixel);

}  // namespace fba::geometry
