#include "fba/grasp/exploration.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>

#include "fba/grasp/angles.hpp"
#include "parallel.hpp"

namespace fba::grasp {
namespace {

// The part [t0, t1] of the segment eye + t * dir, t in [lo, hi], inside box; false when none.
bool clip(const Eigen::AlignedBox3d& box, const Eigen::Vector3d& eye, const Eigen::Vector3d& dir, double lo, double hi,
          double& t0, double& t1) {
  t0 = lo, t1 = hi;
  for (int a = 0; a < 3; ++a) {
    if (std::abs(dir[a]) < 1e-300) {
      if (eye[a] < box.min()[a] || eye[a] > box.max()[a]) return false;
      continue;
    }
    double ta = (box.min()[a] - eye[a]) / dir[a], tb = (box.max()[a] - eye[a]) / dir[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

struct Ray {
  const Octree& model;
  Eigen::Vector3d eye, dir;  // dir reaches the target's centre at t = 1
  double length;             // |dir|
  double t_max;              // where the ray enters the target's box
  const OctreeNode* target;
  // For a surface point: its tangent plane (unit normal; zero for none).
  Eigen::Vector3d plane_point = Eigen::Vector3d::Zero(), plane_normal = Eigen::Vector3d::Zero();
  // Leaves larger than this (a body's coarse inside) are never taken for the point's surface.
  double surface_half_size = std::numeric_limits<double>::infinity();

  // Whether the leaf straddles the tangent plane: part of the surface the point lies on.
  bool on_plane(const OctreeCell& c) const {
    if (plane_normal.isZero() || c.half_size > surface_half_size) return false;
    const double extent = c.half_size * plane_normal.cwiseAbs().sum();
    return std::abs((c.centre - plane_point).dot(plane_normal)) < extent;
  }

  bool blocked(const OctreeCell& c) const {
    if (c.state() == NodeState::Empty || c.node == target) return false;  // first: most cells are empty
    double t0, t1;
    if (!clip(c.box(), eye, dir, 0, t_max, t0, t1)) return false;
    if (c.is_leaf()) return (t1 - t0) * length > 0.5 * c.half_size && !on_plane(c);
    const OctreeNode* k = model.children(*c.node);
    for (int i = 0; i < 8; ++i) {
      const OctreeCell child =
          model.cell(c.depth + 1, 2 * c.x + (i & 1), 2 * c.y + ((i >> 1) & 1), 2 * c.z + ((i >> 2) & 1), k[i]);
      if (blocked(child)) return true;
    }
    return false;
  }
};

// The edge of the model's finest leaves.
double finest_edge(const Octree& model) { return model.bounds.sizes().x() / double(1 << std::clamp(model.max_depth, 0, 30)); }

bool in_view(const Eigen::Isometry3d& world_from_camera, const Eigen::Vector3d& point, double cos_half_fov) {
  const Eigen::Vector3d p = world_from_camera.inverse() * point;
  const double n = p.norm();
  return n > 0 && p.z() >= cos_half_fov * n;
}

// A surface point of the request and the grazing lines of sight the views taken already give it.
struct PointNeed {
  Eigen::Vector3d position, normal;
  int group = 0;
  std::vector<Eigen::Vector3d> grazing;  // unit, eye to point
};

// The request's points that the views taken do not pin down yet (no two grazing lines of sight at
// least the separation apart), with their grazing lines of sight so far. A line of sight counts
// only where the point can be on that view's rim: nothing of the model in front of it or behind it.
std::vector<PointNeed> points_to_pin(const Octree& model, const RegionsOfInterest& regions, std::span<const Eigen::Vector3d> taken) {
  const double sin_rim = std::sin(regions.rim_deg * std::numbers::pi / 180);
  const double cos_separation = std::cos(regions.rim_separation_deg * std::numbers::pi / 180);
  std::vector<PointNeed> out;
  for (const auto& sp : regions.points) {
    PointNeed need{sp.position, sp.normal.normalized(), sp.group, {}};
    for (const auto& eye : taken) {
      const Eigen::Vector3d d = (sp.position - eye).normalized();
      if (std::abs(d.dot(need.normal)) <= sin_rim && !occluded(model, eye, sp.position, need.normal) &&
          !backed(model, eye, sp.position, need.normal))
        need.grazing.push_back(d);
    }
    bool pinned = false;
    for (std::size_t i = 0; i < need.grazing.size() && !pinned; ++i)
      for (std::size_t j = i + 1; j < need.grazing.size() && !pinned; ++j)
        pinned = std::abs(need.grazing[i].dot(need.grazing[j])) <= cos_separation;
    if (!pinned) out.push_back(std::move(need));
  }
  return out;
}

// Refuses parameters out of their ranges, excluded flags that are not one per candidate view, and
// surface points that cannot be grazed (std::invalid_argument, with the values found).
void check_request(const RegionsOfInterest& regions, std::size_t candidates, const std::vector<bool>& excluded,
                   const ExplorationParams& params) {
  if (!(params.movement_weight >= 0) || !(params.half_fov_deg > 0 && params.half_fov_deg < 180) ||
      !(params.min_gain >= 0 && params.min_gain <= 1) || params.max_rays == 0)
    throw std::invalid_argument(fmt::format(
        "exploration parameters: expected movement_weight >= 0, half_fov_deg in (0, 180), min_gain in [0, 1] and "
        "max_rays > 0; found {}, {}, {} and {}",
        params.movement_weight, params.half_fov_deg, params.min_gain, params.max_rays));
  if (!excluded.empty() && excluded.size() != candidates)
    throw std::invalid_argument(fmt::format("exploration: {} excluded flags for {} candidate views; expected one each",
                                            excluded.size(), candidates));

  if (!regions.points.empty() && (!(regions.rim_deg > 0 && regions.rim_deg < 90) ||
                                  !(regions.rim_separation_deg > 0 && regions.rim_separation_deg < 90)))
    throw std::invalid_argument(fmt::format(
        "exploration: a request with surface points needs rim_deg and rim_separation_deg in (0, 90) degrees; found {} and {}",
        regions.rim_deg, regions.rim_separation_deg));
  for (const auto& p : regions.points)
    if (!p.position.allFinite() || !p.normal.allFinite() || p.normal.norm() < 1e-9)
      throw std::invalid_argument(fmt::format(
          "exploration: a requested surface point needs a finite position and a non-zero normal; found ({}, {}, {}) with "
          "normal ({}, {}, {})",
          p.position.x(), p.position.y(), p.position.z(), p.normal.x(), p.normal.y(), p.normal.z()));
}

// What the views look at, the centre a move turns about: the uncertain nodes' mean, else the
// surface points', else the model's root box's centre.
Eigen::Vector3d looked_at(const Octree& model, const std::vector<OctreeCell>& targets, const std::vector<PointNeed>& needs) {
  Eigen::Vector3d centre = model.bounds.center();
  if (!targets.empty()) {
    centre.setZero();
    for (const auto& t : targets) centre += t.centre;
    centre /= double(targets.size());
  } else if (!needs.empty()) {
    centre.setZero();
    for (const auto& p : needs) centre += p.position;
    centre /= double(needs.size());
  }
  return centre;
}

// The view chosen among the scored ones, and why (choice.best, choice.reason): the best score among
// the views not excluded whose gain reaches min_gain; none when no uncertain node is left in the
// `boxes` regions and no view grazes a point, when every view is excluded (visited, or left out by
// the caller), or when none is worth the move.
void pick_view(ViewChoice& choice, std::size_t boxes, std::size_t candidates, double min_gain) {
  const std::string where = fmt::format("{} region{}", boxes, boxes == 1 ? "" : "s");
  if (choice.targets == 0 && !choice.by_points) {
    choice.reason = fmt::format("no uncertain node of the model is left inside the {}", where);
    if (choice.points > 0) choice.reason += fmt::format(", and no unvisited view grazes any of the {} surface points to pin", choice.points);
    return;
  }
  // The best score among the views worth the move: the cost ranks them, it does not disqualify the
  // only views that see enough (a far view that sees much must not lose to a near one that sees nothing).
  const ViewScore* best = nullptr;
  const ViewScore* most = nullptr;  // the unvisited view that sees most
  for (const auto& s : choice.scores) {
    if (s.excluded) continue;
    if (!most || s.gain > most->gain) most = &s;
    if (s.gain >= min_gain && (!best || s.score > best->score)) best = &s;
  }
  if (!most) {
    choice.reason = fmt::format("none of the {} candidate views is left to take (each visited or excluded); {} uncertain nodes remain in the {}",
                                candidates, choice.targets, where);
    return;
  }
  if (!best) {
    choice.reason = fmt::format(
        "no unvisited view is worth the move: the best, view {}, sees {} of the {} uncertain nodes in the {} ({:.1f}%), "
        "below min_gain {:.1f}%",
        most->index, most->seen, choice.rays, where, 100 * most->gain, 100 * min_gain);
    if (choice.points > 0) choice.reason += fmt::format("; none grazes any of the {} surface points to pin in a new direction", choice.points);
    return;
  }
  choice.best = best->index;
  if (choice.by_points) {
    choice.reason = fmt::format(
        "view {} grazes {} of the {} surface points still to pin in a new direction ({} completing a pair, {} for the first "
        "time; gain {:.3f}); moving {:.0f} deg costs {:.3f}: score {:.3f}",
        best->index, best->pins + best->first, choice.points, best->pins, best->first, best->gain,
        best->move_angle * 180 / std::numbers::pi, best->cost, best->score);
    return;
  }
  choice.reason = fmt::format(
      "view {} sees {} of the {} uncertain nodes in the {} ({:.1f}%; {} hidden behind the model, {} out of view); "
      "moving {:.0f} deg costs {:.3f}: score {:.3f}",
      best->index, best->seen, choice.rays, where, 100 * best->gain, best->hidden, best->outside,
      best->move_angle * 180 / std::numbers::pi, best->cost, best->score);
  if (choice.rays < choice.targets) choice.reason += fmt::format(" (one ray per {:.1f} of {} nodes)", double(choice.targets) / choice.rays, choice.targets);
}

}  // namespace

std::vector<OctreeCell> uncertain_targets(const Octree& model, const RegionsOfInterest& regions) {
  std::vector<OctreeCell> out;
  model.for_each_node([&](const OctreeCell& c) {
    if (!c.occupied()) return false;
    const Eigen::AlignedBox3d box = c.box();
    bool meets = false;
    for (const auto& r : regions.boxes) meets |= r.intersects(box);
    if (!meets) return false;
    if (c.is_leaf() && c.state() == NodeState::Partial) out.push_back(c);
    return true;
  });
  return out;
}

bool occluded(const Octree& model, const Eigen::Vector3d& eye, const Eigen::Vector3d& point, const Eigen::Vector3d& normal) {
  if (model.node_count == 0) return false;
  const double edge = finest_edge(model);
  const Eigen::Vector3d probe = point + normal.normalized() * edge;
  Ray ray{model, eye, probe - eye, (probe - eye).norm(), 1, nullptr, point, normal.normalized()};
  if (ray.length <= 0) return false;
  return ray.blocked(model.cell(0, 0, 0, 0, model.root));
}

bool backed(const Octree& model, const Eigen::Vector3d& eye, const Eigen::Vector3d& point, const Eigen::Vector3d& normal) {
  if (model.node_count == 0) return false;
  const double edge = finest_edge(model);
  const Eigen::Vector3d n = normal.normalized();
  Eigen::Vector3d along = point - eye;
  along -= along.dot(n) * n;
  if (!(along.norm() > 1e-12)) return false;  // looking straight at the surface: not a grazing line
  // Far enough to leave the model's box from anywhere inside it.
  const double far = model.bounds.sizes().norm() + (point - model.bounds.center()).norm();
  const Eigen::Vector3d probe = point + n * edge;
  Ray ray{model, probe, along.normalized() * far, far, 1, nullptr, point, n};
  ray.surface_half_size = edge;
  return ray.blocked(model.cell(0, 0, 0, 0, model.root));
}

bool occluded(const Octree& model, const Eigen::Vector3d& eye, const OctreeCell& target) {
  if (model.node_count == 0) return false;
  Ray ray{model, eye, target.centre - eye, (target.centre - eye).norm(), 0, target.node};
  double t0, t1;
  if (ray.length <= 0 || !clip(target.box(), eye, ray.dir, 0, 1, t0, t1)) return false;
  ray.t_max = t0;
  return ray.blocked(model.cell(0, 0, 0, 0, model.root));
}

ViewChoice choose_view(const Octree& model, const RegionsOfInterest& regions,
                       std::span<const Eigen::Isometry3d> candidates, const std::optional<Eigen::Isometry3d>& current,
                       const std::vector<bool>& excluded, const ExplorationParams& params,
                       std::span<const Eigen::Vector3d> taken) {
  check_request(regions, candidates.size(), excluded, params);

  ViewChoice choice;
  const std::vector<PointNeed> needs = points_to_pin(model, regions, taken);
  choice.points = needs.size();
  std::map<int, std::size_t> group_size;
  for (const auto& p : needs) ++group_size[p.group];
  const double sin_rim = std::sin(regions.rim_deg * std::numbers::pi / 180);
  const double cos_separation = std::cos(regions.rim_separation_deg * std::numbers::pi / 180);
  const std::vector<OctreeCell> targets = uncertain_targets(model, regions);
  choice.targets = targets.size();
  choice.rays = std::min(targets.size(), params.max_rays);
  std::vector<const OctreeCell*> rays;
  for (std::size_t i = 0; i < choice.rays; ++i) rays.push_back(&targets[i * targets.size() / choice.rays]);

  const Eigen::Vector3d centre = looked_at(model, targets, needs);
  const double cos_half_fov = std::cos(params.half_fov_deg * std::numbers::pi / 180);

  // Each view's score on its own: at once with a parallel_for.
  choice.scores.resize(candidates.size());
  auto score_points = [&](std::size_t v) {
    ViewScore& s = choice.scores[v];
    s.index = v;
    s.excluded = !excluded.empty() && excluded[v];
    const Eigen::Vector3d eye = candidates[v].translation();
    std::map<int, double> group_gain;  // per group: what this view pins of its points
    for (const PointNeed& p : needs) {
      if (!in_view(candidates[v], p.position, cos_half_fov)) continue;
      const Eigen::Vector3d d = (p.position - eye).normalized();
      if (std::abs(d.dot(p.normal)) > sin_rim) continue;  // not on the rim from here
      bool pins = false;
      for (const auto& g : p.grazing) pins |= std::abs(d.dot(g)) <= cos_separation;
      if (!pins && !p.grazing.empty()) continue;  // a line of sight the views taken already give
      if (occluded(model, eye, p.position, p.normal) || backed(model, eye, p.position, p.normal)) continue;
      ++(pins ? s.pins : s.first);
      group_gain[p.group] += pins ? 1 : 0.5;
    }
    // Mostly the group this view brings nearest to complete, a little all the points it pins.
    double most = 0;
    for (const auto& [g, pinned] : group_gain) most = std::max(most, pinned / double(group_size.at(g)));
    s.point_gain = needs.empty() ? 0 : 0.9 * most + 0.1 * (double(s.pins) + 0.5 * double(s.first)) / double(needs.size());
    if (current) s.move_angle = angle_between(eye - centre, current->translation() - centre);
    s.cost = params.movement_weight * s.move_angle / std::numbers::pi;
  };
  for_each_index(params.parallel_for, candidates.size(), score_points);
  // By the points when some unvisited view grazes them usefully; else by the uncertain nodes (the
  // costly part, rays through the tree: only then).
  for (const auto& s : choice.scores) choice.by_points |= !s.excluded && s.point_gain >= params.min_gain && s.point_gain > 0;
  if (!choice.by_points)
    for_each_index(params.parallel_for, candidates.size(), [&](std::size_t v) {
      ViewScore& s = choice.scores[v];
      const Eigen::Vector3d eye = candidates[v].translation();
      for (const OctreeCell* t : rays) {
        if (!in_view(candidates[v], t->centre, cos_half_fov)) ++s.outside;
        else if (occluded(model, eye, *t)) ++s.hidden;
        else ++s.seen;
      }
      s.node_gain = rays.empty() ? 0 : double(s.seen) / double(rays.size());
    });
  for (auto& s : choice.scores) {
    s.gain = choice.by_points ? s.point_gain : s.node_gain;
    s.score = s.gain - s.cost;
  }

  pick_view(choice, regions.boxes.size(), candidates.size(), params.min_gain);
  return choice;
}

}  // namespace fba::grasp
