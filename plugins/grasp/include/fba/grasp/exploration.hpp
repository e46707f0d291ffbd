// Next best view for grasp-driven exploration. When the request names surface points (the grasp
// candidates' unresolved contacts), the view whose lines of sight graze most of them in a new
// direction: a silhouette fixes the surface only on its rim, and two grazing lines of sight apart
// pin a point down. Otherwise (or when no view grazes any), the view that sees most of the model's
// still-uncertain nodes inside the regions. Either way less the cost of moving there, and
// visibility-aware: a point or node counts for a view only if the ray from the camera centre to it
// crosses no occupied node of the model.
#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "fba/grasp/synthesis.hpp"
#include "fba/types/octree.hpp"
#include "fba/types/regions_of_interest.hpp"

namespace fba::grasp {

struct ExplorationParams {
  // Score = gain - movement_weight * (angle between the current and the candidate camera, seen
  // from the targets' centre, in radians / pi). The gain is the share of target nodes seen, in
  // [0, 1], so a weight of 0.1 trades a half-turn for a tenth of the targets.
  double movement_weight = 0.1;
  // A node is in view when its centre lies within this angle of the optical axis (camera z).
  double half_fov_deg = 30;
  // A view that sees less than this share of the targets is not worth the move.
  double min_gain = 0.01;
  // At most this many target nodes get a ray each (an even stride through them when there are
  // more): the cost is candidates x rays x the depth of the tree.
  std::size_t max_rays = 4096;
  ParallelFor parallel_for;  // the candidate views scored at once (synthesis.hpp); empty: one after another
};

// The uncertain nodes still to observe: Partial leaves of the model that meet a region's box.
std::vector<OctreeCell> uncertain_targets(const Octree& model, const RegionsOfInterest& regions);

struct ViewScore {
  std::size_t index = 0;    // into the candidates
  std::size_t seen = 0;     // target rays that reach their node unobstructed, inside the field of view
  std::size_t hidden = 0;   // in the field of view but behind an occupied node
  std::size_t outside = 0;  // behind the camera or outside its field of view
  // Surface points (RegionsOfInterest::points) this view grazes in a useful direction: `pins`
  // complete a pair with a grazing view already taken, `first` are the first grazing view of theirs.
  std::size_t pins = 0;
  std::size_t first = 0;
  // 0.9 x the largest share of one group's points still to pin that it pins (first ones count
  // half) + 0.1 x that share over all points: completing one grasp candidate comes first.
  double point_gain = 0;
  double node_gain = 0;     // seen / rays (seen, hidden, outside and node_gain: only when the choice is by the nodes)
  double gain = 0;          // point_gain when the choice is by points, else node_gain
  double move_angle = 0;    // radians from the current camera, around the targets' centre
  double cost = 0;          // movement_weight * move_angle / pi
  double score = 0;         // gain - cost
  bool excluded = false;    // visited, or left out by the caller: never chosen
};

struct ViewChoice {
  std::optional<std::size_t> best;  // none: no candidate is worth the move (reason says why)
  std::vector<ViewScore> scores;    // one per candidate, in their order
  std::size_t targets = 0;          // uncertain nodes inside the regions
  std::size_t rays = 0;             // targets given a ray (at most max_rays)
  std::size_t points = 0;           // surface points of the request not yet pinned by two views taken
  bool by_points = false;           // chosen by grazing the points (else by the uncertain nodes)
  std::string reason;               // human-readable: what was chosen and why, or why nothing
};

// Whether the segment from eye to the target's box crosses an occupied node of the model other
// than the target. Grazing contacts (the ray running through less than half of a node's
// half-size) do not block, so that a surface node is not hidden by its neighbours on the surface.
bool occluded(const Octree& model, const Eigen::Vector3d& eye, const OctreeCell& target);

// Whether the segment from eye to the surface point (moved one finest leaf edge out along its
// normal) crosses an occupied leaf of the model that does not straddle the point's tangent plane.
// A line of sight that grazes a flat face runs along it: the face's own voxel staircase is the
// surface the view pins, not something hiding it. A leaf wholly in front of the plane (another part
// of the object) or behind it (the body, seen through from behind the rim) blocks.
bool occluded(const Octree& model, const Eigen::Vector3d& eye, const Eigen::Vector3d& point, const Eigen::Vector3d& normal);

// Whether the model stands behind the surface point seen from eye: the line of sight continued past
// the point, along its tangent plane and one finest leaf edge out, meets an occupied leaf. The point
// then projects inside the silhouette, not on its rim (a handle in front of the tool's head), and
// that view cannot pin it. Fine leaves straddling the tangent plane are the point's own surface.
bool backed(const Octree& model, const Eigen::Vector3d& eye, const Eigen::Vector3d& point, const Eigen::Vector3d& normal);

// Scores every candidate (world_from_camera poses, camera z forward) and picks the best one that
// is not excluded. current: where the camera is now (no movement cost without it). excluded: one
// flag per candidate (may be empty). taken: the camera centres of the views the model already has
// (what the request's points were judged against). Throws std::invalid_argument on parameters out of range or an
// excluded list of the wrong length, naming the values.
ViewChoice choose_view(const Octree& model, const RegionsOfInterest& regions,
                       std::span<const Eigen::Isometry3d> candidates,
                       const std::optional<Eigen::Isometry3d>& current = std::nullopt,
                       const std::vector<bool>& excluded = {}, const ExplorationParams& params = {},
                       std::span<const Eigen::Vector3d> taken = {});

}  // namespace fba::grasp
