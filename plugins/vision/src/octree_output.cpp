// Reading results out of an Octree: leaves, surface mesh, PLY, re-projection, comparisons.
#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <unordered_map>

#include "fba/geometry/mesh_io.hpp"
#include "fba/geometry/renderer.hpp"
#include "fba/vision/octree_carver.hpp"

namespace fba::vision {

namespace {

bool occupied(const fba::OctreeNode& n) { return n.state != fba::NodeState::Empty; }

Eigen::AlignedBox3d box_of(const fba::OctreeNode& n) {
  const Eigen::Vector3d c = n.centre.cast<double>();
  const Eigen::Vector3d h = Eigen::Vector3d::Constant(n.half_size);
  return {c - h, c + h};
}

std::size_t leaves_under(const fba::Octree& t, std::size_t i) {
  const auto& n = t.nodes[i];
  if (n.is_leaf()) return 1;
  std::size_t s = 0;
  for (int c = 0; c < 8; ++c) s += leaves_under(t, static_cast<std::size_t>(n.first_child + c));
  return s;
}

std::size_t mismatches(const fba::Octree& a, std::size_t ia, const fba::Octree& b, std::size_t ib) {
  const auto& na = a.nodes[ia];
  const auto& nb = b.nodes[ib];
  if (na.is_leaf() && nb.is_leaf()) return na.state != nb.state ? 1 : 0;
  if (na.is_leaf()) return 1;
  if (nb.is_leaf()) return leaves_under(a, ia);
  std::size_t s = 0;
  for (int c = 0; c < 8; ++c)
    s += mismatches(a, static_cast<std::size_t>(na.first_child + c), b, static_cast<std::size_t>(nb.first_child + c));
  return s;
}

// Builds the boundary between occupied and non-occupied space from the tree itself, so a large
// leaf costs no more than a small one. Node cells are kept on the integer lattice of the finest
// level, so neighbours are found exactly and face corners are shared (welded) between faces.
class SurfaceBuilder {
 public:
  explicit SurfaceBuilder(const fba::Octree& t) : t_(t) {}

  fba::TriangleMesh build() {
    if (t_.nodes.empty()) return std::move(mesh_);
    int finest = 0;
    for (const auto& n : t_.nodes) finest = std::max<int>(finest, n.depth);
    n_ = 1 << finest;
    // Cells from the root down; children are ordered x, then y, then z (bit 0, 1, 2).
    cells_.resize(t_.nodes.size());
    cells_[0] = {0, 0, 0, n_};
    std::vector<std::size_t> stack{0};
    while (!stack.empty()) {
      const std::size_t i = stack.back();
      stack.pop_back();
      if (t_.nodes[i].is_leaf()) continue;
      const Cell& c = cells_[i];
      const int h = c.s / 2;
      for (int k = 0; k < 8; ++k) {
        const std::size_t j = static_cast<std::size_t>(t_.nodes[i].first_child + k);
        cells_[j] = {c.x[0] + (k & 1) * h, c.x[1] + ((k >> 1) & 1) * h, c.x[2] + ((k >> 2) & 1) * h, h};
        stack.push_back(j);
      }
    }
    for (std::size_t i = 0; i < t_.nodes.size(); ++i) {
      if (!t_.nodes[i].is_leaf() || !occupied(t_.nodes[i])) continue;
      const Cell& c = cells_[i];
      for (int axis = 0; axis < 3; ++axis)
        for (int dir : {-1, 1}) {
          const int plane = c.x[axis] + (dir > 0 ? c.s : 0);
          int q[3] = {c.x[0], c.x[1], c.x[2]};
          q[axis] += dir * c.s;
          if (q[axis] < 0 || q[axis] >= n_) {
            face(axis, dir, plane, c);  // the root's boundary: outside is not occupied
            continue;
          }
          across(node_at(q, c.s), axis, dir, plane, c);
        }
    }
    return std::move(mesh_);
  }

 private:
  struct Cell {
    int x[3];  // min corner, finest-lattice units
    int s;     // edge
  };

  // The node of edge >= s containing lattice point q: a leaf, or a node of edge s.
  std::size_t node_at(const int q[3], int s) const {
    std::size_t i = 0;
    while (!t_.nodes[i].is_leaf() && cells_[i].s > s) {
      const Cell& c = cells_[i];
      const int h = c.s / 2;
      const int k = (q[0] >= c.x[0] + h ? 1 : 0) | (q[1] >= c.x[1] + h ? 2 : 0) | (q[2] >= c.x[2] + h ? 4 : 0);
      i = static_cast<std::size_t>(t_.nodes[i].first_child + k);
    }
    return i;
  }

  // The face of occupied leaf `own` at `plane`, seen against node j across it: emitted where j's
  // leaves that touch the face are not occupied, as one square per such leaf (or the whole face
  // when j is a leaf at least as large).
  void across(std::size_t j, int axis, int dir, int plane, const Cell& own) {
    const fba::OctreeNode& n = t_.nodes[j];
    if (n.is_leaf()) {
      if (!occupied(n)) face(axis, dir, plane, cells_[j].s < own.s ? cells_[j] : own);
      return;
    }
    // Children on the near side: their `axis` bit is 0 when j lies on the + side of the face.
    const int near = dir > 0 ? 0 : 1;
    for (int k = 0; k < 8; ++k)
      if (((k >> axis) & 1) == near) across(static_cast<std::size_t>(n.first_child + k), axis, dir, plane, own);
  }

  // A square in the plane axis = plane covering cell c's extent along the two other axes, two
  // triangles wound counter-clockwise seen from the side `dir` points to.
  void face(int axis, int dir, int plane, const Cell& c) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const int su[4] = {0, 1, 1, 0}, sv[4] = {0, 0, 1, 1};
    int idx[4];
    for (int i = 0; i < 4; ++i) {
      int p[3];
      p[axis] = plane;
      p[u] = c.x[u] + su[i] * c.s;
      p[v] = c.x[v] + sv[i] * c.s;
      idx[i] = vertex(p);
    }
    // (u, v, axis) is right-handed, so u x v points along +axis: keep the order for +dir.
    if (dir > 0) {
      mesh_.triangles.emplace_back(idx[0], idx[1], idx[2]);
      mesh_.triangles.emplace_back(idx[0], idx[2], idx[3]);
    } else {
      mesh_.triangles.emplace_back(idx[0], idx[2], idx[1]);
      mesh_.triangles.emplace_back(idx[0], idx[3], idx[2]);
    }
  }

  int vertex(const int p[3]) {
    // Coordinates are at most 2^19 (depth <= 19): 21 bits each.
    const std::uint64_t key = std::uint64_t(p[0]) | std::uint64_t(p[1]) << 21 | std::uint64_t(p[2]) << 42;
    const auto [it, inserted] = vertex_index_.emplace(key, static_cast<int>(mesh_.vertices.size()));
    if (inserted) {
      const double unit = t_.bounds.sizes().x() / n_;
      mesh_.vertices.push_back((t_.bounds.min() + unit * Eigen::Vector3d(p[0], p[1], p[2])).cast<float>());
    }
    return it->second;
  }

  const fba::Octree& t_;
  int n_ = 1;
  std::vector<Cell> cells_;
  std::unordered_map<std::uint64_t, int> vertex_index_;
  fba::TriangleMesh mesh_;
};

}  // namespace

std::vector<Eigen::AlignedBox3d> occupied_leaves(const fba::Octree& t) {
  std::vector<Eigen::AlignedBox3d> out;
  for (const auto& n : t.nodes)
    if (n.is_leaf() && occupied(n)) out.push_back(box_of(n));
  return out;
}

fba::TriangleMesh occupied_surface_mesh(const fba::Octree& t) {
  return SurfaceBuilder(t).build();
}

void write_ply(const fba::Octree& t, const std::string& path) { geometry::write_ply(occupied_surface_mesh(t), path); }

cv::Mat reproject_mask(const fba::Octree& t, const fba::CameraModel& cam) {
  // The renderer samples pixel centres, the rule the silhouettes follow (a rendered mask, or a
  // thresholded image); filling each leaf's outline with cv::fillConvexPoly instead would add
  // about half a pixel all round and bias the IoU against the model.
  return geometry::render(occupied_surface_mesh(t), cam).mask;
}

double mask_iou(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size()) throw std::invalid_argument("mask_iou: masks of different sizes");
  const cv::Mat ia = a != 0, ib = b != 0;
  const double inter = cv::countNonZero(ia & ib), uni = cv::countNonZero(ia | ib);
  return uni == 0 ? 1.0 : inter / uni;
}

std::size_t count_leaf_mismatches(const fba::Octree& a, const fba::Octree& b) {
  if (a.nodes.empty()) return b.nodes.empty() ? 0 : 1;
  if (b.nodes.empty() || !a.bounds.isApprox(b.bounds)) return leaves_under(a, 0);
  return mismatches(a, 0, b, 0);
}

}  // namespace fba::vision
