#include "fba/vision/reference_carve.hpp"

#include <chrono>

#include "carve_common.hpp"
#include "fba/geometry/mesh_io.hpp"

namespace fba::vision {

using namespace detail;

namespace {

// The plainest projection: each corner through P.
Rect reference_rect(const ViewData& v, const Lattice& L, const NodeKey& k, double tol) {
  const int s = cells_at_depth(k.depth);
  Rect r;
  double umin = INFINITY, umax = -INFINITY, vmin = INFINITY, vmax = -INFINITY;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d X = L.corner(k.ix + (c & 1) * s, k.iy + ((c >> 1) & 1) * s, k.iz + ((c >> 2) & 1) * s);
    const Eigen::Vector3d p = v.P * X.homogeneous();
    if (!(p.z() > 0)) {
      r.behind = true;
      return r;
    }
    umin = std::min(umin, p.x() / p.z()), umax = std::max(umax, p.x() / p.z());
    vmin = std::min(vmin, p.y() / p.z()), vmax = std::max(vmax, p.y() / p.z());
  }
  return pixel_rect(umin, umax, vmin, vmax, tol);
}

bool reference_leaf_carved_by(const ViewData& v, const Lattice& L, const NodeKey& k, const Rect& r, double tol) {
  const int h = cells_at_depth(k.depth) / 2;
  const Eigen::Vector3d p = v.P * L.corner(k.ix + h, k.iy + h, k.iz + h).homogeneous();
  return p.z() > 0 && leaf_carved_by(v, r, p.x() / p.z(), p.y() / p.z(), tol);
}

}  // namespace

fba::Octree reference_carve(const std::vector<fba::Silhouette>& views, const Eigen::AlignedBox3d& bounds,
                            const CarverParams& params, const fba::RegionsOfInterest& roi, CarveStats* stats) {
  check_params(params);
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<ViewData> vd;
  for (const auto& s : views) vd.push_back(make_view(s, params.curvature_threshold));

  const Eigen::AlignedBox3d cube = geometry::cube_around(bounds);
  const Lattice L{cube.min(), cube.sizes().x()};
  fba::Octree tree;
  tree.bounds = cube;
  tree.max_depth = params.max_depth;
  tree.views = static_cast<int>(views.size());
  std::vector<NodeKey> keys{NodeKey{}};
  tree.nodes.emplace_back();
  std::size_t refined = 0;

  // Algorithm 1: level by level; Algorithm 2 for each node of the level.
  for (std::size_t begin = 0, end = 1; begin < end; begin = end, end = tree.nodes.size()) {
    for (std::size_t i = begin; i < end; ++i) {
      const NodeKey k = keys[i];
      double min_occ = 1, max_occ = 0;
      bool empty = false, curvature_hit = false;
      std::vector<Rect> rects(vd.size());
      for (std::size_t vi = 0; vi < vd.size(); ++vi) {
        const ViewData& v = vd[vi];
        const Rect r = rects[vi] = reference_rect(v, L, k, params.silhouette_tolerance);
        const Occupancy o = occupancy(v, r);
        empty = empty || o.empty();
        min_occ = std::min(min_occ, o.value());
        max_occ = std::max(max_occ, o.value());
        curvature_hit = curvature_hit || (!o.full() && graspable_contour_in(v, r));
      }
      fba::OctreeNode& n = tree.nodes[i];
      set_geometry(n, L, k);
      const Split split = split_decision(params, L, k.depth, min_occ, max_occ, intersects_roi(roi, L, k), curvature_hit);
      if (!empty && split == Split::No && wants_leaf_test(params, L, k.depth, min_occ))
        for (std::size_t vi = 0; vi < vd.size(); ++vi)
          empty = empty || reference_leaf_carved_by(vd[vi], L, k, rects[vi], params.silhouette_tolerance);
      if (empty) {
        n.state = fba::NodeState::Empty;
        n.occupancy = 0;
        continue;
      }
      n.occupancy = static_cast<float>(min_occ);
      if (split == Split::No) {
        n.state = min_occ >= 1 ? fba::NodeState::Full : fba::NodeState::Partial;
        continue;
      }
      n.state = fba::NodeState::Partial;
      n.interest = split == Split::Grasp ? 1.0f : 0.0f;
      n.first_child = static_cast<std::int32_t>(tree.nodes.size());
      ++refined;
      for (int c = 0; c < 8; ++c) {
        keys.push_back(k.child(c));
        tree.nodes.emplace_back();  // invalidates n; not used below
      }
    }
  }
  if (stats) {
    stats->views = views.size();
    stats->nodes_visited = tree.nodes.size();
    stats->nodes_refined = refined;
    stats->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  return tree;
}

}  // namespace fba::vision
