// Where a simulated object stands on the table, shared by sim.camera and sim.hand so that the
// camera renders the object the hand grasps. Header only: the camera does not link the physics.
#pragma once

#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>

#include "fba/types/mesh.hpp"

namespace fba::sim_hand {

// The mesh (metres, z up) laid on the table in its resting orientation, turned by yaw about z,
// moved by (x, y), and raised or lowered so that its lowest point rests on the table (z = 0).
struct ObjectPlacement {
  double x = 0;
  double y = 0;
  double yaw = 0;  // radians
  // "upright": as the mesh file stands; "side": laid on its side (turned 90 degrees about the
  // mesh's x axis, before the yaw).
  std::string rest = "upright";
};

inline Eigen::Matrix3f placement_rotation(const ObjectPlacement& p) {
  if (p.rest != "upright" && p.rest != "side")
    throw std::invalid_argument("object placement: rest must be 'upright' or 'side', found '" + p.rest + "'");
  const Eigen::Matrix3f yaw = Eigen::AngleAxisf(static_cast<float>(p.yaw), Eigen::Vector3f::UnitZ()).toRotationMatrix();
  if (p.rest == "upright") return yaw;
  return yaw * Eigen::AngleAxisf(static_cast<float>(M_PI / 2), Eigen::Vector3f::UnitX()).toRotationMatrix();
}

// The mesh turned and moved by the placement but not raised: the "mesh" frame of sim.camera and
// sim.hand (the mesh file's coordinates, where a task without a table describes the object).
// raise: set to how far it must go up to rest on the table.
inline TriangleMesh place_in_mesh_frame(const TriangleMesh& mesh, const ObjectPlacement& placement, double& raise) {
  const Eigen::Matrix3f r = placement_rotation(placement);
  TriangleMesh placed = mesh;
  float min_z = INFINITY;
  for (auto& v : placed.vertices) {
    v = r * v + Eigen::Vector3f(static_cast<float>(placement.x), static_cast<float>(placement.y), 0);
    min_z = std::min(min_z, v.z());
  }
  raise = placed.vertices.empty() ? 0.0 : -static_cast<double>(min_z);
  return placed;
}

// The mesh moved to its place on the table (the "table" frame: the table is z = 0).
inline TriangleMesh place_on_table(const TriangleMesh& mesh, const ObjectPlacement& placement) {
  double raise = 0;
  TriangleMesh placed = place_in_mesh_frame(mesh, placement, raise);
  for (auto& v : placed.vertices) v.z() += static_cast<float>(raise);
  return placed;
}

}  // namespace fba::sim_hand
