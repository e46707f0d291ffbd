// The ply_leaves parameter as the components that write carved models to PLY declare it:
// vision.octree_carver (model.ply) and grasp.synthesis (exploration/model_<views>views.ply).
// Declared once here, with its name, default, choices and meaning, so that the two cannot read
// the same word differently.
#pragma once

#include <string>

#include <fba/component.hpp>

#include "fba/vision/octree_carver.hpp"

namespace fba::vision {

struct PlyLeavesParameter {
  static constexpr auto kPlyLeaves = fba::Param<std::string>(
      "ply_leaves", "seen",
      "which occupied leaves the models written as PLY hold (vision.octree_carver's model.ply, grasp.synthesis's "
      "exploration/model_<views>views.ply): seen, those two views saw whole (the object as the views show it; space no view "
      "could carve, such as the top of a root box no camera framed, is left out), or occupied, every one (the model as "
      "synthesis analyses it and the checks use it)")
                                         .choices({"seen", "occupied"});

  // The leaves a value of kPlyLeaves names (the loader has checked it is one of its choices).
  static PlyLeaves named(const std::string& value) { return value == "occupied" ? PlyLeaves::Occupied : PlyLeaves::Seen; }
  static PlyLeaves read(const fba::Context& ctx) { return named(ctx(kPlyLeaves)); }
};

}  // namespace fba::vision
