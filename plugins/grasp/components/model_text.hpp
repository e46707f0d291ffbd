// How grasp.synthesis words a model in its messages: numbers, the root box, the faces of it the
// model reaches, why a model gives no surface to grasp, and why its candidates give no grasp.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include <fba/types/octree.hpp>

#include "fba/grasp/model_surface.hpp"
#include "fba/grasp/synthesis.hpp"

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

inline double total_of(const GraspCandidate* c) { return c ? c->grasp.scores.total : 0.0; }

// Which criteria held a candidate back: what a user tunes (weights, hand geometry) or learns
// about the object.
inline std::string criteria(const GraspCandidate& c) {
  return " (S1 symmetry " + fixed(c.grasp.scores.symmetry) + ", S3 safety margin " + fixed(c.grasp.scores.safety_margin) +
         ", S4 curvature " + fixed(c.grasp.scores.curvature) + ")";
}

// Why the last view's candidates (`r`; `best`: the best total of all) give no reliable grasp at
// `threshold`: what removed them, or what held back the best one on resolved surface. `rims`:
// contacts are resolved when two views' rims pin them (rim_deg).
inline std::string no_reliable_grasp_reason(const SynthesisResult& r, int views, const GraspCandidate* best, double threshold,
                                            bool rims) {
  std::string reason = "no reliable grasp after " + std::to_string(views) + " views: ";
  if (r.candidates.empty()) {  // what removed them, not a best total of nothing
    if (r.below_table > 0 || r.hand_unfit > 0 || r.too_low > 0)
      return reason + "no candidate the hand can reach: " + std::to_string(r.below_table) +
             " would put the hand into the table (as a pinch too), " + std::to_string(r.hand_unfit) + " wider than the hand takes; " +
             std::to_string(r.too_low) + " surface samples too low for a finger to touch above the table";
    if (r.hand_blocked > 0 || r.asymmetric > 0 || r.not_force_closure > 0)
      return reason + "no candidate the hand can take: " + std::to_string(r.hand_blocked) + " blocked by the model in the hand's way, " +
             std::to_string(r.asymmetric) + " with S1 under min_symmetry, " + std::to_string(r.not_force_closure) +
             " not force closure on the model";
    return reason + "no candidate the hand can reach";
  }
  // The best on resolved surface: of the candidates whose contacts and surroundings are resolved,
  // all below the threshold here (a reliable one the arm could not reach is not weighed).
  const GraspCandidate* best_resolved = nullptr;
  for (const auto& c : r.candidates)
    if (!c.uncertain && c.grasp.scores.total < threshold && c.grasp.scores.total > total_of(best_resolved)) best_resolved = &c;
  if (!best_resolved) {
    // Nothing to weigh against the threshold: the model never resolved where the candidates are.
    return reason + "none of the " + std::to_string(r.candidates.size()) +
           " candidates has its contacts and the surface around them resolved" + (rims ? " (pinned by two views' rims)" : "") +
           ", nor a reliable one its contacts; the best, of total " + fixed(total_of(best)) + criteria(*best) +
           ", touches a part of the model not yet resolved (threshold " + fixed(threshold) + ")";
  }
  reason += "best total " + fixed(total_of(best_resolved)) + criteria(*best_resolved) + " < threshold " + fixed(threshold);
  if (total_of(best) > total_of(best_resolved))
    reason += " (a candidate of total " + fixed(total_of(best)) + " touches a part of the model not yet resolved)";
  return reason;
}

}  // namespace fba::grasp
