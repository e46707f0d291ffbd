// How grasp.synthesis words a model in its messages: numbers, the root box, the faces of it the
// model reaches, and why a model gives no surface to grasp.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include <fba/types/octree.hpp>

#include "fba/grasp/model_surface.hpp"

namespace fba::grasp {

inline std::string fixed(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", v);
  return buf;
}

inline std::string box_text(const Eigen::AlignedBox3d& b) {
  return "[" + fixed(b.min().x()) + ", " + fixed(b.min().y()) + ", " + fixed(b.min().z()) + ", " + fixed(b.max().x()) + ", " +
         fixed(b.max().y()) + ", " + fixed(b.max().z()) + "]";
}

// The faces of the model's root box that its occupied leaves touch, as "x = 0.130 and z = 0.240";
// empty when none does.
inline std::string bounds_reached(const fba::Octree& model) {
  bool at[6] = {};  // -x, -y, -z, +x, +y, +z
  model.for_each_occupied_leaf([&](const fba::OctreeCell& c) {
    const int last = (1 << c.depth) - 1;
    const int corner[3] = {c.x, c.y, c.z};
    for (int a = 0; a < 3; ++a) {
      at[a] |= corner[a] == 0;
      at[a + 3] |= corner[a] == last;
    }
  });
  std::vector<std::string> faces;
  for (int f = 0; f < 6; ++f)
    if (at[f]) faces.push_back(std::string(1, "xyz"[f % 3]) + " = " + fixed(f < 3 ? model.bounds.min()[f] : model.bounds.max()[f - 3]));
  std::string text;
  for (std::size_t i = 0; i < faces.size(); ++i) text += (i == 0 ? "" : i + 1 == faces.size() ? " and " : ", ") + faces[i];
  return text;
}

// Why the model gives no surface to grasp, "" when it gives one: no occupied leaf joined to the
// table, or no occupied leaf at all.
inline std::string empty_surface_reason(const fba::Octree& model, const ModelSurface& surface, int views, double table_z) {
  if (!surface.samples.empty()) return "";
  if (surface.leaves > 0) {
    const std::string table = "none of its " + std::to_string(surface.leaves) + " occupied leaves after " + std::to_string(views) +
                              " views is joined to the table at z = " + fixed(table_z);
    // An object outside the workspace is seen through it: the views' cones cross the root box
    // and end on its faces, away from the table.
    if (const std::string faces = bounds_reached(model); !faces.empty())
      return "the carved model reaches the workspace's bounds at " + faces + " (the carver's root box " + box_text(model.bounds) +
             "), and " + table + ": the object may be larger than or outside the workspace";
    return "none of the model's " + std::to_string(surface.leaves) + " occupied leaves after " + std::to_string(views) +
           " views is joined to the table at z = " + fixed(table_z) +
           ": the object rests on it (check table_z, and the carver's bounds reach down to it)";
  }
  return "the model is empty after " + std::to_string(views) +
         " views: no occupied leaf to grasp (no target in the silhouettes, or the object outside the workspace, the carver's "
         "root box " + box_text(model.bounds) + ")";
}

}  // namespace fba::grasp
