// The reference carve, written apart from the fast carver on purpose: its own image sums, corner
// projection, occupancy, split decision and leaf test, straight from the rules in
// octree_carver.hpp, so that "0 mismatches" checks the fast carver's criteria as well as its
// traversal. Plain and tight: one thread, every node tested against the views in order until one
// empties it, the 8 corners projected through P, one summed-area lookup per node and view, no
// allocation per node.
#include "fba/vision/reference_carve.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "fba/geometry/mesh_io.hpp"

namespace fba::vision {

namespace {

// Corner coordinates: the root's edge divided into 2^20 cells (as the fast carver does, so that
// both see the same corners bit for bit).
constexpr int kBits = 20;
constexpr double kInv = 1.0 / double(1 << kBits);

struct View {
  Eigen::Matrix<double, 3, 4> P;
  int w = 0, h = 0;
  const std::uint8_t* mask = nullptr;  // row-major, w per row
  std::size_t step = 0;
  std::vector<std::int64_t> sum;        // (w + 1) x (h + 1): silhouette pixels above-left
  std::vector<std::int64_t> grasp_sum;  // the same for graspable contour points; empty when off
  bool outside_empty = false;           // pixels outside the image are empty, not unknown
  std::int64_t box(const std::vector<std::int64_t>& s, int x0, int y0, int x1, int y1) const {
    const auto at = [&](int x, int y) { return s[std::size_t(y) * std::size_t(w + 1) + std::size_t(x)]; };
    return at(x1 + 1, y1 + 1) - at(x0, y1 + 1) - at(x1 + 1, y0) + at(x0, y0);
  }
};

std::vector<std::int64_t> summed_area(int w, int h, const auto& in) {
  std::vector<std::int64_t> s(std::size_t(w + 1) * std::size_t(h + 1), 0);
  for (int y = 0; y < h; ++y) {
    std::int64_t row = 0;
    for (int x = 0; x < w; ++x) {
      row += in(x, y) ? 1 : 0;
      s[std::size_t(y + 1) * std::size_t(w + 1) + std::size_t(x + 1)] = s[std::size_t(y) * std::size_t(w + 1) + std::size_t(x + 1)] + row;
    }
  }
  return s;
}

View prepare(const fba::Silhouette& s, const CarverParams& p) {
  const double curvature_threshold = p.curvature_threshold;
  if (!s.frame) throw std::invalid_argument("reference_carve: the silhouette has no frame (camera)");
  if (s.mask.empty() || s.mask.type() != CV_8UC1 || !s.mask.isContinuous())
    throw std::invalid_argument("reference_carve: expected a continuous 8-bit single-channel silhouette mask");
  View v;
  v.P = s.frame->camera.projection();
  v.w = s.mask.cols, v.h = s.mask.rows;
  v.mask = s.mask.data;
  v.step = s.mask.step;
  v.outside_empty = p.carve_outside_view && !s.touches_border;
  v.sum = summed_area(v.w, v.h, [&](int x, int y) { return v.mask[std::size_t(y) * v.step + std::size_t(x)] != 0; });
  if (std::isfinite(curvature_threshold)) {
    // Points of the outer contour and of every hole's contour (both outline of the object).
    std::vector<std::uint8_t> g(std::size_t(v.w) * std::size_t(v.h), 0);
    std::vector<const fba::Outline*> outlines{&s};
    for (const auto& h : s.holes) outlines.push_back(&h);
    for (const fba::Outline* o : outlines)
      for (std::size_t i = 0; i < o->contour.size() && i < o->curvature.size(); ++i) {
        const cv::Point q = o->contour[i];
        if (o->curvature[i] < curvature_threshold && q.x >= 0 && q.y >= 0 && q.x < v.w && q.y < v.h)
          g[std::size_t(q.y) * std::size_t(v.w) + std::size_t(q.x)] = 1;
      }
    v.grasp_sum = summed_area(v.w, v.h, [&](int x, int y) { return g[std::size_t(y) * std::size_t(v.w) + std::size_t(x)] != 0; });
  }
  return v;
}

struct Key {
  int x, y, z, depth;  // min corner in lattice cells
};

// The pixels within tol of the projected corners' bounding box (pixel centres at integers, a
// pixel the unit square around its centre), or behind: a corner not in front of the camera.
struct PixelBox {
  int x0, y0, x1, y1;
  bool behind;
};

int up(double v) { return static_cast<int>(std::ceil(std::clamp(v, -1e8, 1e8))); }
int down(double v) { return static_cast<int>(std::floor(std::clamp(v, -1e8, 1e8))); }

struct Carve {
  const std::vector<View>& views;
  const CarverParams& p;
  const fba::RegionsOfInterest& roi;
  Eigen::Vector3d origin;
  double edge;

  Eigen::Vector3d point(int ix, int iy, int iz) const {
    return origin + edge * Eigen::Vector3d(ix * kInv, iy * kInv, iz * kInv);
  }
  int cells(int depth) const { return 1 << (kBits - depth); }
  bool at_limit(int depth) const { return depth >= p.max_depth || edge * cells(depth) * kInv <= p.min_node_size; }

  PixelBox pixels(const View& v, const Key& k) const {
    const int s = cells(k.depth);
    double u0 = INFINITY, u1 = -INFINITY, w0 = INFINITY, w1 = -INFINITY;
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3d q = v.P * point(k.x + (c & 1) * s, k.y + ((c >> 1) & 1) * s, k.z + ((c >> 2) & 1) * s).homogeneous();
      if (!(q.z() > 0)) return {0, 0, -1, -1, true};
      u0 = std::min(u0, q.x() / q.z()), u1 = std::max(u1, q.x() / q.z());
      w0 = std::min(w0, q.y() / q.z()), w1 = std::max(w1, q.y() / q.z());
    }
    const double g = p.silhouette_tolerance + 0.5;
    return {up(u0 - g), up(w0 - g), down(u1 + g), down(w1 + g), false};
  }

  // Silhouette pixels plus pixels outside the image, over the box's area. Nothing is known
  // behind the camera, nor outside the image unless the view saw the whole object there
  // (outside_empty): occupied.
  std::pair<std::int64_t, std::int64_t> occupied(const View& v, const PixelBox& b) const {
    if (b.behind) return {1, 1};
    const std::int64_t area = std::int64_t(b.x1 - b.x0 + 1) * (b.y1 - b.y0 + 1);
    const int x0 = std::max(b.x0, 0), x1 = std::min(b.x1, v.w - 1), y0 = std::max(b.y0, 0), y1 = std::min(b.y1, v.h - 1);
    const std::int64_t outside = v.outside_empty ? 0 : 1;
    if (x0 > x1 || y0 > y1) return {area * outside, area};
    return {v.box(v.sum, x0, y0, x1, y1) + (area - std::int64_t(x1 - x0 + 1) * (y1 - y0 + 1)) * outside, area};
  }

  // The share over the projected node: among the pixels whose centre's ray meets the node's cube
  // (the cube's projection, found in 3D here rather than as a 2D hull), those in the silhouette
  // or outside the image. No such pixel: the box's share. Clamped into (0, 1): only asked for a
  // node that its box finds neither empty nor full.
  double share(const View& v, const Key& k, double box_share) const {
    const int s = cells(k.depth);
    const Eigen::Vector3d lo = point(k.x, k.y, k.z), hi = point(k.x + s, k.y + s, k.z + s);
    const Eigen::Matrix3d M = v.P.leftCols<3>();
    const Eigen::Matrix3d Minv = M.inverse();
    const Eigen::Vector3d C = -Minv * v.P.col(3);
    double u0 = INFINITY, u1 = -INFINITY, w0 = INFINITY, w1 = -INFINITY;
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3d q = v.P * point(k.x + (c & 1) * s, k.y + ((c >> 1) & 1) * s, k.z + ((c >> 2) & 1) * s).homogeneous();
      if (!(q.z() > 0)) return std::clamp(box_share, 1e-9, 1 - 1e-9);
      u0 = std::min(u0, q.x() / q.z()), u1 = std::max(u1, q.x() / q.z());
      w0 = std::min(w0, q.y() / q.z()), w1 = std::max(w1, q.y() / q.z());
    }
    std::int64_t n = 0, occupied = 0;
    for (int y = up(w0); y <= down(w1); ++y)
      for (int x = up(u0); x <= down(u1); ++x) {
        const Eigen::Vector3d d = Minv * Eigen::Vector3d(x, y, 1);
        double t0 = 0, t1 = INFINITY;  // slab test of the ray C + t d, t > 0
        for (int a = 0; a < 3 && t0 <= t1; ++a) {
          if (d[a] == 0) {
            if (C[a] < lo[a] || C[a] > hi[a]) t0 = 1, t1 = 0;
            continue;
          }
          const double ta = (lo[a] - C[a]) / d[a], tb = (hi[a] - C[a]) / d[a];
          t0 = std::max(t0, std::min(ta, tb)), t1 = std::min(t1, std::max(ta, tb));
        }
        if (t0 > t1) continue;
        ++n;
        const bool outside = x < 0 || y < 0 || x >= v.w || y >= v.h;
        occupied += outside ? !v.outside_empty : v.mask[std::size_t(y) * v.step + std::size_t(x)] != 0;
      }
    return std::clamp(n > 0 ? double(occupied) / double(n) : box_share, 1e-9, 1 - 1e-9);
  }

  bool graspable(const View& v, const PixelBox& b) const {
    if (v.grasp_sum.empty() || b.behind) return false;
    const int x0 = std::max(b.x0, 0), x1 = std::min(b.x1, v.w - 1), y0 = std::max(b.y0, 0), y1 = std::min(b.y1, v.h - 1);
    return x0 <= x1 && y0 <= y1 && v.box(v.grasp_sum, x0, y0, x1, y1) > 0;
  }

  bool in_roi(const Key& k) const {
    const int s = cells(k.depth);
    const Eigen::AlignedBox3d box(point(k.x, k.y, k.z), point(k.x + s, k.y + s, k.z + s));
    return std::any_of(roi.boxes.begin(), roi.boxes.end(), [&](const auto& b) { return !b.isEmpty() && b.intersects(box); });
  }

  // A leaf at the limit is carved by a view that sees all of it (box inside the image, or outside
  // pixels known empty) when no
  // silhouette pixel's square lies within tol of its centre's projection.
  bool leaf_carved(const View& v, const Key& k, const PixelBox& b) const {
    if (b.behind || (!v.outside_empty && (b.x0 < 0 || b.y0 < 0 || b.x1 >= v.w || b.y1 >= v.h))) return false;
    const int h = cells(k.depth) / 2;
    const Eigen::Vector3d q = v.P * point(k.x + h, k.y + h, k.z + h).homogeneous();
    if (!(q.z() > 0)) return false;
    const double u = q.x() / q.z(), w = q.y() / q.z(), tol = p.silhouette_tolerance, g = tol + 0.5;
    const int x0 = std::max(up(u - g), 0), x1 = std::min(down(u + g), v.w - 1);
    const int y0 = std::max(up(w - g), 0), y1 = std::min(down(w + g), v.h - 1);
    if (x0 > x1 || y0 > y1) return v.outside_empty;  // the window is wholly outside the image
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const double dx = std::max(std::abs(x - u) - 0.5, 0.0), dy = std::max(std::abs(y - w) - 0.5, 0.0);
        if (v.mask[std::size_t(y) * v.step + std::size_t(x)] != 0 && dx * dx + dy * dy <= tol * tol) return false;
      }
    return true;
  }
};

}  // namespace

fba::Octree reference_carve(const std::vector<fba::Silhouette>& silhouettes, const Eigen::AlignedBox3d& bounds,
                            const CarverParams& params, const fba::RegionsOfInterest& roi, CarveStats* stats) {
  if (params.max_depth < 0 || params.max_depth >= kBits)
    throw std::invalid_argument("reference_carve: max_depth: expected 0..19, found " + std::to_string(params.max_depth));
  if (!(params.silhouette_tolerance >= 0 && params.silhouette_tolerance <= 64) || params.min_node_size < 0 ||
      !(params.occupancy_threshold >= 0 && params.occupancy_threshold <= 1))
    throw std::invalid_argument("reference_carve: expected silhouette_tolerance in 0..64 px, min_node_size >= 0 and "
                                "occupancy_threshold in 0..1");
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<View> views;
  for (const auto& s : silhouettes) views.push_back(prepare(s, params));

  const Eigen::AlignedBox3d cube = geometry::cube_around(bounds);
  const Carve carve{views, params, roi, cube.min(), cube.sizes().x()};
  fba::Octree tree;
  tree.bounds = cube;
  tree.max_depth = params.max_depth;
  tree.views = static_cast<int>(views.size());
  std::vector<PixelBox> boxes(views.size());
  // A Partial node's share lies in (0, 1): only a threshold between decides by it.
  const bool share_decides = params.occupancy_threshold > 0 && params.occupancy_threshold < 1;
  std::size_t visited = 0, refined = 0;

  // Algorithm 1: level by level; Algorithm 2 for each node of the level.
  std::vector<std::pair<fba::OctreeNode*, Key>> level{{&tree.root, Key{0, 0, 0, 0}}}, next;
  while (!level.empty()) {
    next.clear();
    for (const auto& [n, k] : level) {
      ++visited;
      double lo = 1;
      bool empty = false, grasp = false, generic = false;
      for (std::size_t i = 0; i < views.size() && !empty; ++i) {
        boxes[i] = carve.pixels(views[i], k);
        const auto [occ, area] = carve.occupied(views[i], boxes[i]);
        empty = occ == 0;
        lo = std::min(lo, double(occ) / double(area));
        // The generic criterion: a view where the node is on the outline finds its share above the threshold.
        if (!empty && occ != area && !generic)
          generic = (share_decides ? carve.share(views[i], k, double(occ) / double(area)) : 0.5) > params.occupancy_threshold;
        grasp = grasp || (occ != area && carve.graspable(views[i], boxes[i]));
      }
      bool split = false, interest = false;
      if (!empty && lo < 1 && !carve.at_limit(k.depth)) {
        generic = generic && k.depth < params.generic_depth;
        split = generic || grasp || carve.in_roi(k);
        interest = split && !generic;
        split = split && !(int(views.size()) < params.detail_after_views && k.depth >= params.detail_depth);
      }
      if (!empty && !split && lo < 1 && carve.at_limit(k.depth))
        for (std::size_t i = 0; i < views.size() && !empty; ++i) empty = carve.leaf_carved(views[i], k, boxes[i]);
      if (empty) {
        n->set_state(fba::NodeState::Empty);
        n->set_occupancy(0);
        continue;
      }
      n->set_occupancy(lo < 1 ? std::min(static_cast<float>(lo), 0.99999994f) : 1.0f);
      if (!split) {
        n->set_state(lo >= 1 ? fba::NodeState::Full : fba::NodeState::Partial);
        continue;
      }
      n->set_state(fba::NodeState::Partial);
      n->set_interest(interest);
      fba::OctreeNode* c = tree.split(*n, fba::NodeState::Partial);
      ++refined;
      const int h = carve.cells(k.depth + 1);
      for (int i = 0; i < 8; ++i)
        next.emplace_back(c + i, Key{k.x + (i & 1) * h, k.y + ((i >> 1) & 1) * h, k.z + ((i >> 2) & 1) * h, k.depth + 1});
    }
    std::swap(level, next);
  }
  if (stats) {
    stats->views = views.size();
    stats->nodes_visited = visited;
    stats->nodes_refined = refined;
    stats->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  return tree;
}

}  // namespace fba::vision
