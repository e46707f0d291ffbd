// A small software rasteriser for simulated cameras and for pictures of models.
//
// Ideal pinhole only: the CameraModel's K and pose are used, its distortion is ignored.
// Pixel (u, v) is sampled at its centre, which OpenCV puts at coordinates (u, v), so a world
// point projects onto the same pixel here as with cv::projectPoints.
#pragma once

#include <cstdint>
#include <optional>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "fba/types/camera.hpp"
#include "fba/types/mesh.hpp"

namespace fba::geometry {

struct RenderOptions {
  // Colours are BGR, 0..255.
  cv::Vec3b object_colour{70, 150, 230};
  // The background is a vertical gradient from top to bottom (equal colours: flat).
  cv::Vec3b background_top{35, 35, 35};
  cv::Vec3b background_bottom{95, 95, 95};

  // An infinite table plane z = table_z (world) under the object. It hides any part of the
  // object below it, is drawn as a two-tone checkerboard of tile size table_tile (metres; 0 for
  // a plain table) and never enters the mask or the depth image.
  bool table = false;
  double table_z = 0.0;
  cv::Vec3b table_colour{120, 160, 170};
  double table_tile = 0.05;

  // Lambert + ambient: intensity = ambient + diffuse * max(0, n . l), with n the face normal
  // turned towards the camera (faces are shaded on both sides, so winding does not matter).
  // light_towards_world: unit direction from the scene towards a directional light, in world
  // coordinates; unset = a headlight shining along the camera's viewing direction.
  std::optional<Eigen::Vector3d> light_towards_world;
  double ambient = 0.25;
  double diffuse = 0.75;

  // Additive Gaussian noise on the colour image (standard deviation in grey levels); the same
  // seed gives the same noise. Depth and mask are never noisy.
  double noise_sigma = 0.0;
  std::uint64_t seed = 0;

  // Geometry closer than this (camera z, metres) is clipped away.
  double near_plane = 1e-3;
};

struct RenderResult {
  cv::Mat colour;  // CV_8UC3, BGR
  cv::Mat depth;   // CV_32FC1, camera z of the object surface in metres, 0 where no object
  cv::Mat mask;    // CV_8UC1, 255 where the object is visible, 0 elsewhere
};

// Renders `mesh` as seen by `camera` (width x height from the camera). Z-buffered with
// perspective-correct depth; triangles crossing the near plane are clipped. Throws
// std::invalid_argument for a camera without a positive image size.
RenderResult render(const TriangleMesh& mesh, const CameraModel& camera,
                    const RenderOptions& options = {});

// A scene of parts in colours of their own, rendered one render() each with the same camera:
// `part`'s surface replaces `into`'s colour, depth and mask wherever it is nearer than what `into`
// shows there (or `into` shows no surface), so that the parts hide one another as in one render.
// `into`'s background and table stay where no part's surface is drawn. Throws
// std::invalid_argument when the two are not the same size and types as render() makes them.
void composite(RenderResult& into, const RenderResult& part);

}  // namespace fba::geometry
