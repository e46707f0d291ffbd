#include "fba/grasp/exploration.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>

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

  bool blocked(const OctreeCell& c) const {
    double t0, t1;
    if (!clip(c.box(), eye, dir, 0, t_max, t0, t1)) return false;
    if (c.state() == NodeState::Empty || c.node == target) return false;
    if (c.is_leaf()) return (t1 - t0) * length > 0.5 * c.half_size;
    const OctreeNode* k = model.children(*c.node);
    for (int i = 0; i < 8; ++i) {
      const OctreeCell child =
          model.cell(c.depth + 1, 2 * c.x + (i & 1), 2 * c.y + ((i >> 1) & 1), 2 * c.z + ((i >> 2) & 1), k[i]);
      if (blocked(child)) return true;
    }
    return false;
  }
};

bool in_view(const Eigen::Isometry3d& world_from_camera, const Eigen::Vector3d& point, double cos_half_fov) {
  const Eigen::Vector3d p = world_from_camera.inverse() * point;
  const double n = p.norm();
  return n > 0 && p.z() >= cos_half_fov * n;
}

double angle_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double n = a.norm() * b.norm();
  if (n <= 0) return 0;
  return std::acos(std::clamp(a.dot(b) / n, -1.0, 1.0));
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
                       const std::vector<bool>& excluded, const ExplorationParams& params) {
  if (!(params.movement_weight >= 0) || !(params.half_fov_deg > 0 && params.half_fov_deg < 180) ||
      !(params.min_gain >= 0 && params.min_gain <= 1) || params.max_rays == 0)
    throw std::invalid_argument(fmt::format(
        "exploration parameters: expected movement_weight >= 0, half_fov_deg in (0, 180), min_gain in [0, 1] and "
        "max_rays > 0; found {}, {}, {} and {}",
        params.movement_weight, params.half_fov_deg, params.min_gain, params.max_rays));
  if (!excluded.empty() && excluded.size() != candidates.size())
    throw std::invalid_argument(fmt::format("exploration: {} excluded flags for {} candidate views; expected one each",
                                            excluded.size(), candidates.size()));

  ViewChoice choice;
  const std::vector<OctreeCell> targets = uncertain_targets(model, regions);
  choice.targets = targets.size();
  choice.rays = std::min(targets.size(), params.max_rays);
  std::vector<const OctreeCell*> rays;
  for (std::size_t i = 0; i < choice.rays; ++i) rays.push_back(&targets[i * targets.size() / choice.rays]);

  Eigen::Vector3d centre = model.bounds.center();
  if (!targets.empty()) {
    centre.setZero();
    for (const auto& t : targets) centre += t.centre;
    centre /= double(targets.size());
  }
  const double cos_half_fov = std::cos(params.half_fov_deg * std::numbers::pi / 180);

  for (std::size_t v = 0; v < candidates.size(); ++v) {
    ViewScore s;
    s.index = v;
    s.excluded = !excluded.empty() && excluded[v];
    const Eigen::Vector3d eye = candidates[v].translation();
    for (const OctreeCell* t : rays) {
      if (!in_view(candidates[v], t->centre, cos_half_fov)) ++s.outside;
      else if (occluded(model, eye, *t)) ++s.hidden;
      else ++s.seen;
    }
    s.gain = rays.empty() ? 0 : double(s.seen) / double(rays.size());
    if (current) s.move_angle = angle_between(eye - centre, current->translation() - centre);
    s.cost = params.movement_weight * s.move_angle / std::numbers::pi;
    s.score = s.gain - s.cost;
    choice.scores.push_back(s);
  }

  const std::string where = fmt::format("{} region{}", regions.boxes.size(), regions.boxes.size() == 1 ? "" : "s");
  if (targets.empty()) {
    choice.reason = fmt::format("no uncertain node of the model is left inside the {}", where);
    return choice;
  }
  const ViewScore* best = nullptr;
  for (const auto& s : choice.scores)
    if (!s.excluded && (!best || s.score > best->score)) best = &s;
  if (!best) {
    choice.reason = fmt::format("all {} candidate views have been visited; {} uncertain nodes remain in the {}",
                                candidates.size(), targets.size(), where);
    return choice;
  }
  if (best->gain < params.min_gain) {
    const ViewScore* most = best;
    for (const auto& s : choice.scores)
      if (!s.excluded && s.gain > most->gain) most = &s;
    choice.reason = fmt::format(
        "no unvisited view is worth the move: the best, view {}, sees {} of the {} uncertain nodes in the {} ({:.1f}%), "
        "below min_gain {:.1f}%",
        most->index, most->seen, rays.size(), where, 100 * most->gain, 100 * params.min_gain);
    return choice;
  }
  choice.best = best->index;
  choice.reason = fmt::format(
      "view {} sees {} of the {} uncertain nodes in the {} ({:.1f}%; {} hidden behind the model, {} out of view); "
      "moving {:.0f} deg costs {:.3f}: score {:.3f}",
      best->index, best->seen, rays.size(), where, 100 * best->gain, best->hidden, best->outside,
      best->move_angle * 180 / std::numbers::pi, best->cost, best->score);
  if (rays.size() < targets.size()) choice.reason += fmt::format(" (one ray per {:.1f} of {} nodes)", double(targets.size()) / rays.size(), targets.size());
  return choice;
}

}  // namespace fba::grasp
