// The object and its placement as parameters, declared once for sim.camera and sim.hand: a task
// gives both the same values, and the camera renders the object where the hand grasps it.
#pragma once

#include <filesystem>
#include <string>

#include <fba/component.hpp>

#include "object_placement.hpp"

namespace fba::sim_hand {

inline constexpr Param<std::filesystem::path> kObjectMesh{
    "mesh", required, "the object: any mesh assimp reads (OBJ, PLY, STL...), metres, z up; it rests on the table at z = 0"};
inline constexpr auto kObjectX = Param<double>("object_x", 0.0, "the object's position on the table, metres").range(-1, 1);
inline constexpr auto kObjectY = Param<double>("object_y", 0.0, "the object's position on the table, metres").range(-1, 1);
inline constexpr auto kObjectYaw = Param<double>("object_yaw", 0.0, "the object's turn about z, degrees").range(-360, 360);
inline constexpr auto kObjectRest =
    Param<std::string>("object_rest", "upright",
                       "how the object lies on the table: as the mesh stands, or on its side (turned 90 deg about the mesh's x)")
        .choices({"upright", "side"});

// The placement the component's parameters give.
inline ObjectPlacement object_placement(Context& ctx) {
  constexpr double kDegree = M_PI / 180.0;
  return {ctx(kObjectX), ctx(kObjectY), ctx(kObjectYaw) * kDegree, ctx(kObjectRest)};
}

}  // namespace fba::sim_hand
