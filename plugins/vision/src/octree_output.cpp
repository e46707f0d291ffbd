// Reading results out of an Octree: leaves, surface mesh, PLY, re-projection, comparisons.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "fba/geometry/mesh_io.hpp"
#include "fba/geometry/renderer.hpp"
#include "fba/geometry/voxelize.hpp"
#include "fba/vision/octree_carver.hpp"

namespace fba::vision {

namespace {

bool occupied(const fba::OctreeNode& n) { return n.state() != fba::NodeState::Empty; }

std::size_t leaves_under(const fba::Octree& t, const fba::OctreeNode& n) {
  if (n.is_leaf()) return 1;
  std::size_t s = 0;
  const fba::OctreeNode* c = t.children(n);
  for (int i = 0; i < 8; ++i) s += leaves_under(t, c[i]);
  return s;
}

std::size_t mismatches(const fba::Octree& a, const fba::OctreeNode& na, const fba::Octree& b, const fba::OctreeNode& nb) {
  if (na.is_leaf() && nb.is_leaf()) return na.state() != nb.state() ? 1 : 0;
  if (na.is_leaf()) return 1;
  if (nb.is_leaf()) return leaves_under(a, na);
  std::size_t s = 0;
  const fba::OctreeNode* ca = a.children(na);
  const fba::OctreeNode* cb = b.children(nb);
  for (int i = 0; i < 8; ++i) s += mismatches(a, ca[i], b, cb[i]);
  return s;
}

// Builds the boundary between occupied and non-occupied space from the tree itself, so a large
// leaf costs no more than a small one. Node cells are kept on the integer lattice of the finest
// level, so neighbours are found exactly and face corners are shared (welded) between faces.
class SurfaceBuilder {
 public:
  SurfaceBuilder(const fba::Octree& t, const LeafFilter& inside) : t_(t), inside_(inside) {}

  fba::TriangleMesh build() {
    if (t_.node_count == 0) return std::move(mesh_);
    t_.for_each_leaf([&](const fba::OctreeCell& c) { finest_ = std::max(finest_, c.depth); });
    n_ = 1 << finest_;
    path_[0] = {&t_.root, {{0, 0, 0}, n_}};
    visit(0);
    return std::move(mesh_);
  }

 private:
  struct Cell {
    int x[3];  // min corner, finest-lattice units
    int s;     // edge
    bool contains(const int q[3]) const {
      return q[0] >= x[0] && q[1] >= x[1] && q[2] >= x[2] && q[0] < x[0] + s && q[1] < x[1] + s && q[2] < x[2] + s;
    }
  };
  struct Step {
    const fba::OctreeNode* node;
    Cell cell;
  };

  // Depth first over the occupied leaves, keeping their ancestors in path_, so that a neighbour
  // is looked up from the nearest common ancestor rather than from the root.
  void visit(int d) {
    const Step& st = path_[d];
    if (!occupied(*st.node)) return;
    if (st.node->is_leaf()) {
      if (inside(*st.node, st.cell)) faces_of(d);
      return;
    }
    const fba::OctreeNode* c = t_.children(*st.node);
    const int h = st.cell.s / 2;
    for (int k = 0; k < 8; ++k) {
      path_[d + 1] = {&c[k], {{st.cell.x[0] + (k & 1) * h, st.cell.x[1] + ((k >> 1) & 1) * h, st.cell.x[2] + ((k >> 2) & 1) * h}, h}};
      visit(d + 1);
    }
  }

  void faces_of(int d) {
    const Cell c = path_[d].cell;
    for (int axis = 0; axis < 3; ++axis)
      for (int dir : {-1, 1}) {
        const int plane = c.x[axis] + (dir > 0 ? c.s : 0);
        int q[3] = {c.x[0], c.x[1], c.x[2]};
        q[axis] += dir * c.s;
        if (q[axis] < 0 || q[axis] >= n_) {
          face(axis, dir, plane, c);  // the root's boundary: outside is not occupied
          continue;
        }
        int a = d - 1;  // d >= 1 here: the root's neighbours are all outside
        while (!path_[a].cell.contains(q)) --a;
        // Down to the node of edge >= c.s containing q: a leaf, or a node of c's edge.
        const fba::OctreeNode* n = path_[a].node;
        Cell nc = path_[a].cell;
        while (!n->is_leaf() && nc.s > c.s) {
          const int h = nc.s / 2;
          const int bx = q[0] >= nc.x[0] + h, by = q[1] >= nc.x[1] + h, bz = q[2] >= nc.x[2] + h;
          n = &t_.children(*n)[bx | by << 1 | bz << 2];
          nc = {{nc.x[0] + bx * h, nc.x[1] + by * h, nc.x[2] + bz * h}, h};
        }
        across(*n, nc, axis, dir, plane, c);
      }
  }

  // The face of occupied leaf `own` at `plane`, seen against node n (cell nc) across it: emitted
  // where n's leaves that touch the face are not occupied, as one square per such leaf (or the
  // whole face when n is a leaf at least as large).
  void across(const fba::OctreeNode& n, const Cell& nc, int axis, int dir, int plane, const Cell& own) {
    if (n.is_leaf()) {
      if (!inside(n, nc)) face(axis, dir, plane, nc.s < own.s ? nc : own);
      return;
    }
    // Children on the near side: their `axis` bit is 0 when n lies on the + side of the face.
    const int near = dir > 0 ? 0 : 1;
    const int h = nc.s / 2;
    const fba::OctreeNode* c = t_.children(n);
    for (int k = 0; k < 8; ++k)
      if (((k >> axis) & 1) == near)
        across(c[k], Cell{{nc.x[0] + (k & 1) * h, nc.x[1] + ((k >> 1) & 1) * h, nc.x[2] + ((k >> 2) & 1) * h}, h}, axis,
               dir, plane, own);
  }

  // Whether leaf n (cell c) is in the solid: occupied, and kept by the filter if there is one.
  bool inside(const fba::OctreeNode& n, const Cell& c) const {
    if (!occupied(n)) return false;
    if (!inside_) return true;
    const int depth = finest_ - std::countr_zero(static_cast<unsigned>(c.s));
    return inside_(t_.cell(depth, c.x[0] / c.s, c.x[1] / c.s, c.x[2] / c.s, n));
  }

  // The square in the plane axis = plane covering cell c's extent along the two other axes, facing
  // the side `dir` points to.
  void face(int axis, int dir, int plane, const Cell& c) {
    geometry::add_lattice_square(mesh_, axis, dir, plane, c.x, c.s, [this](const int p[3]) { return vertex(p); });
  }

  // Welds face corners: lattice point -> vertex index, in an open-addressing table (a node-based
  // map cost more than the rest of the mesh at depth 9).
  int vertex(const int p[3]) {
    // Coordinates are at most 2^19 (depth <= 19): 21 bits each, so ~0 is never a key.
    const std::uint64_t key = std::uint64_t(p[0]) | std::uint64_t(p[1]) << 21 | std::uint64_t(p[2]) << 42;
    if (2 * (mesh_.vertices.size() + 1) > keys_.size()) grow();
    const std::size_t mask = keys_.size() - 1;
    for (std::size_t i = (key * 0x9E3779B97F4A7C15ull) >> shift_;; i = (i + 1) & mask) {
      if (keys_[i] == key) return values_[i];
      if (keys_[i] == kNoKey) {
        keys_[i] = key;
        values_[i] = static_cast<int>(mesh_.vertices.size());
        const double unit = t_.bounds.sizes().x() / n_;
        mesh_.vertices.push_back((t_.bounds.min() + unit * Eigen::Vector3d(p[0], p[1], p[2])).cast<float>());
        return values_[i];
      }
    }
  }

  void grow() {
    std::vector<std::uint64_t> keys = std::move(keys_);
    std::vector<int> values = std::move(values_);
    const std::size_t size = std::max<std::size_t>(1024, 2 * keys.size());
    keys_.assign(size, kNoKey);
    values_.assign(size, 0);
    shift_ = 64 - std::countr_zero(size);
    for (std::size_t j = 0; j < keys.size(); ++j) {
      if (keys[j] == kNoKey) continue;
      std::size_t i = (keys[j] * 0x9E3779B97F4A7C15ull) >> shift_;
      while (keys_[i] != kNoKey) i = (i + 1) & (size - 1);
      keys_[i] = keys[j];
      values_[i] = values[j];
    }
  }

  const fba::Octree& t_;
  const LeafFilter& inside_;
  int finest_ = 0;
  int n_ = 1;
  static constexpr std::uint64_t kNoKey = ~std::uint64_t(0);
  std::vector<std::uint64_t> keys_;
  std::vector<int> values_;
  int shift_ = 64;
  Step path_[32];  // the node being visited and its ancestors, root first (depth <= 19)
  fba::TriangleMesh mesh_;
};

}  // namespace

std::vector<Eigen::AlignedBox3d> occupied_leaves(const fba::Octree& t) {
  std::vector<Eigen::AlignedBox3d> out;
  t.for_each_occupied_leaf([&](const fba::OctreeCell& c) { out.push_back(c.box()); });
  return out;
}

fba::TriangleMesh occupied_surface_mesh(const fba::Octree& t) { return SurfaceBuilder(t, {}).build(); }

fba::TriangleMesh surface_mesh(const fba::Octree& t, const LeafFilter& keep) { return SurfaceBuilder(t, keep).build(); }

void write_ply(const fba::Octree& t, const std::string& path) { geometry::write_ply(occupied_surface_mesh(t), path); }

bool seen_by_two_views(const fba::OctreeCell& leaf, const std::vector<fba::CameraModel>& views) {
  // A view sees the whole leaf when the projection of the sphere around it is inside the image:
  // the carver never carves a node partly outside an image on that image's evidence.
  const double radius = std::sqrt(3.0) * leaf.half_size;
  auto sees = [&](const fba::CameraModel& camera) {
    const Eigen::Vector3d p = camera.camera_from_world * leaf.centre;
    if (p.z() <= radius) return false;
    const double margin = camera.K(0, 0) * radius / (p.z() - radius);
    const double u = camera.K(0, 0) * p.x() / p.z() + camera.K(0, 2), v = camera.K(1, 1) * p.y() / p.z() + camera.K(1, 2);
    return u >= margin - 0.5 && v >= margin - 0.5 && u <= camera.width - 0.5 - margin && v <= camera.height - 0.5 - margin;
  };
  const std::ptrdiff_t need = std::min<std::ptrdiff_t>(2, std::ssize(views));
  std::ptrdiff_t seen = 0;
  for (const auto& v : views)
    if (sees(v) && ++seen >= need) return true;
  return need == 0;
}

fba::TriangleMesh ply_mesh(const fba::Octree& t, PlyLeaves leaves, const std::vector<fba::CameraModel>& views) {
  if (leaves == PlyLeaves::Occupied) return occupied_surface_mesh(t);
  return surface_mesh(t, [&](const fba::OctreeCell& c) { return seen_by_two_views(c, views); });
}

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
  if (a.node_count == 0) return b.node_count == 0 ? 0 : 1;
  if (b.node_count == 0 || !a.bounds.isApprox(b.bounds)) return leaves_under(a, a.root);
  return mismatches(a, a.root, b, b.root);
}

}  // namespace fba::vision
