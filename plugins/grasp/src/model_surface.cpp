#include "fba/grasp/model_surface.hpp"

#include "neighbour_grid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <unordered_set>

#include <Eigen/Eigenvalues>
#include <opencv2/core.hpp>

namespace fba::grasp {
namespace {

// The leaf holding p, as for_each_occupied_leaf gives it; its node is null outside the root box.
OctreeCell leaf_at(const Octree& model, const Eigen::Vector3d& p) {
  OctreeCell c;
  if (!model.bounds.contains(p)) return c;
  c.node = &model.root;
  Eigen::Vector3d lo = model.bounds.min();
  Eigen::Vector3i lattice = Eigen::Vector3i::Zero();
  double edge = model.bounds.sizes().x();
  while (!c.node->is_leaf()) {
    edge /= 2;
    ++c.depth;
    lattice *= 2;
    int i = 0;
    for (int a = 0; a < 3; ++a)
      if (p[a] >= lo[a] + edge) {
        i |= 1 << a;
        lo[a] += edge;
        ++lattice[a];
      }
    c.node = &model.children(*c.node)[i];
  }
  c.x = lattice.x(), c.y = lattice.y(), c.z = lattice.z();
  c.half_size = edge / 2;
  c.centre = lo + Eigen::Vector3d::Constant(c.half_size);
  return c;
}

bool occupied_leaf(const OctreeCell& c) { return c.node && c.occupied(); }

// A leaf's identity: its depth (5 bits) and lattice position (19 bits per axis; model_surface
// refuses deeper models).
constexpr int kMaxKeyDepth = 19;
std::uint64_t leaf_key(const OctreeCell& c) {
  return (static_cast<std::uint64_t>(c.depth) << 57) | (static_cast<std::uint64_t>(c.x) << 38) |
         (static_cast<std::uint64_t>(c.y) << 19) | static_cast<std::uint64_t>(c.z);
}

// Calls f(axis, sign, leaf, quarters) for the leaves just beyond each of the cell's six faces: the
// leaf at the face's centre when it is as large as the cell or larger, as it then covers the whole
// face (quarters 4; beyond the root box's faces, a cell with a null node); else the leaf at each of
// the face's four quarter points (quarters 1), which finds the finer neighbours there.
template <class F>
void for_face_neighbours(const Octree& model, const OctreeCell& c, F&& f) {
  const double h = c.half_size, eps = 1e-3 * h;
  for (int a = 0; a < 3; ++a) {
    const int u = (a + 1) % 3, v = (a + 2) % 3;
    for (int sign : {-1, 1}) {
      Eigen::Vector3d centre = c.centre;
      centre[a] += sign * (h + eps);
      if (const OctreeCell n = leaf_at(model, centre); !n.node || n.depth <= c.depth) {
        f(a, sign, n, 4);
        continue;
      }
      for (int qu : {-1, 1})
        for (int qv : {-1, 1}) {
          Eigen::Vector3d p = centre;
          p[u] += qu * h / 2;
          p[v] += qv * h / 2;
          f(a, sign, leaf_at(model, p), 1);
        }
    }
  }
}

// The occupied leaves an object resting on the table can be (keys as leaf_key): those joined
// through shared faces to a leaf that reaches down to the table. A pillar the views could not
// carve stays joined; space above the object that no view saw (carving keeps it: nothing there
// was seen to be empty), cut off from the object by carved space, does not.
struct SupportedLeaves {
  std::unordered_set<std::uint64_t> keys;
  std::size_t unsupported = 0;
};

SupportedLeaves supported_leaves(const Octree& model, double table_z) {
  SupportedLeaves out;
  std::size_t occupied = 0;
  std::vector<OctreeCell> queue;
  model.for_each_occupied_leaf([&](const OctreeCell& c) {
    ++occupied;
    if (c.centre.z() - c.half_size <= table_z && out.keys.insert(leaf_key(c)).second) queue.push_back(c);
  });
  while (!queue.empty()) {
    const OctreeCell c = queue.back();
    queue.pop_back();
    for_face_neighbours(model, c, [&](int, int, const OctreeCell& n, int) {
      if (occupied_leaf(n) && out.keys.insert(leaf_key(n)).second) queue.push_back(n);
    });
  }
  out.unsupported = occupied - out.keys.size();
  return out;
}

}  // namespace

ModelSurface model_surface(const Octree& model, const ModelSurfaceParams& params) {
  if (params.radius < 0) throw std::invalid_argument("model surface: radius must be >= 0, found " + std::to_string(params.radius));
  ModelSurface out;
  if (model.node_count == 0) return out;
  const Eigen::Vector3d size = model.bounds.sizes();
  if (!(size.x() > 0) || std::abs(size.y() - size.x()) > 1e-9 * size.x() || std::abs(size.z() - size.x()) > 1e-9 * size.x())
    throw std::invalid_argument("model surface: the octree's root box must be a cube of positive size; found sizes " +
                                std::to_string(size.x()) + " x " + std::to_string(size.y()) + " x " + std::to_string(size.z()));

  // Surface leaves and their free faces. A face whose neighbour is finer is probed at its four
  // quarter points just outside it, so a coarse leaf next to finer ones sees a free finer one too.
  struct Raw {
    Eigen::Vector3d position, free_direction;
    bool uncertain;
  };
  std::vector<Raw> raw;
  int finest_depth = -1;
  if (params.table_z && model.max_depth > kMaxKeyDepth)
    throw std::invalid_argument("model surface: with a table, models up to depth " + std::to_string(kMaxKeyDepth) +
                                " are supported; found max_depth " + std::to_string(model.max_depth));
  SupportedLeaves supported;
  if (params.table_z) supported = supported_leaves(model, *params.table_z);
  out.unsupported_leaves = supported.unsupported;
  auto is_object = [&](const OctreeCell& c) {
    return occupied_leaf(c) && (!params.table_z || supported.keys.contains(leaf_key(c)));
  };
  model.for_each_occupied_leaf([&](const OctreeCell& c) {
    ++out.leaves;
    if (!is_object(c)) return;
    finest_depth = std::max(finest_depth, c.depth);
    const double h = c.half_size, eps = 1e-3 * h;
    Eigen::Vector3d free_direction = Eigen::Vector3d::Zero();  // towards the faces no object leaf is beyond
    for_face_neighbours(model, c, [&](int a, int sign, const OctreeCell& n, int quarters) {
      if (!is_object(n)) free_direction[a] += sign * quarters / 4.0;
    });
    bool any_free = false;
    for (int a = 0; a < 3; ++a) any_free = any_free || free_direction[a] != 0;
    // Faces free on both sides of an axis cancel there (a wall one leaf thick): such a leaf is
    // surface too, its direction left to the neighbours' fit.
    if (!any_free) {
      bool two_sided = false;
      for (int a = 0; a < 3 && !two_sided; ++a) {
        Eigen::Vector3d lo = c.centre, hi = c.centre;
        lo[a] -= h + eps;
        hi[a] += h + eps;
        two_sided = !is_object(leaf_at(model, lo)) && !is_object(leaf_at(model, hi));
      }
      if (!two_sided) return;
    }
    const Eigen::Vector3d position = c.centre + h * free_direction.cwiseMax(-1.0).cwiseMin(1.0);
    if (params.table_z && position.z() < *params.table_z) return;  // the model's cone below the table
    raw.push_back({position, free_direction, c.state() == NodeState::Partial && c.depth < model.max_depth});
  });
  if (raw.empty()) return out;
  out.finest_edge = size.x() / double(std::int64_t(1) << finest_depth);
  out.radius = params.radius > 0 ? params.radius : 3 * out.finest_edge;

  std::vector<SurfaceSample> s(raw.size());
  for (std::size_t i = 0; i < raw.size(); ++i) s[i].position = raw[i].position, s[i].uncertain = raw[i].uncertain;
  const std::vector<std::vector<std::size_t>> neighbourhoods = NeighbourGrid(s, out.radius).neighbourhoods(true);
  std::vector<SurfaceSample> smoothed = s;
  for (std::size_t i = 0; i < s.size(); ++i) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero(), direction = Eigen::Vector3d::Zero();
    const std::vector<std::size_t>& nb = neighbourhoods[i];
    for (std::size_t j : nb) {
      mean += s[j].position;
      direction += raw[j].free_direction;
    }
    mean /= double(nb.size());
    Eigen::Vector3d normal = direction;
    if (nb.size() >= 6) {
      Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
      for (std::size_t j : nb) cov += (s[j].position - mean) * (s[j].position - mean).transpose();
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
      // A fit only where the neighbours spread in two directions: a line of points has no plane.
      if (eig.eigenvalues()[1] > 1e-12 * out.radius * out.radius) {
        normal = eig.eigenvectors().col(0);
        if (normal.dot(direction) < 0) normal = -normal;
        if (direction.squaredNorm() == 0) normal = Eigen::Vector3d::Zero();
      }
    }
    if (normal.squaredNorm() == 0) normal = raw[i].free_direction;
    if (normal.squaredNorm() == 0) normal = s[i].position - model.bounds.center();  // a lone voxel: away from the centre
    if (normal.squaredNorm() == 0) normal = Eigen::Vector3d::UnitZ();
    normal.normalize();
    smoothed[i].normal = normal;
    // Onto the fitted plane: removes the voxel staircase that would read as curvature.
    smoothed[i].position = s[i].position + (mean - s[i].position).dot(normal) * normal;
  }
  estimate_curvature(smoothed, out.radius);
  out.samples = std::move(smoothed);
  return out;
}

SilhouetteRim silhouette_rim(const Silhouette& silhouette) {
  if (!silhouette.frame || !silhouette.frame->has_pose)
    throw std::invalid_argument("silhouette rim: the silhouette's frame has no camera pose; a rim needs the view's pose");
  const CameraModel& camera = silhouette.frame->camera;
  if (!camera.distortion.empty() && cv::countNonZero(camera.distortion) > 0)
    throw std::invalid_argument("silhouette rim: the camera has lens distortion; expected the undistorted frame contour extraction gives");
  SilhouetteRim rim;
  rim.camera = camera;
  const Eigen::Matrix3d to_world = camera.camera_from_world.linear().transpose();
  auto add = [&](const Outline& o) {
    for (std::size_t i = 0; i < o.contour.size() && i < o.normals.size(); ++i) {
      const cv::Point2d& q = o.contour[i];
      constexpr double kBorder = 1.5;  // the image's edge, where the outline is the border, not the object's rim
      if (q.x < kBorder || q.y < kBorder || q.x > camera.width - 1 - kBorder || q.y > camera.height - 1 - kBorder) continue;
      const cv::Point2d& m = o.normals[i];
      // The image line through q across the normal, positive outside; its plane through the eye has
      // normal K^T l in the camera's frame, outward (l . K X = depth * l . x > 0 outside).
      const Eigen::Vector3d line(m.x, m.y, -(m.x * q.x + m.y * q.y));
      const Eigen::Vector3d n = to_world * (camera.K.transpose() * line);
      if (n.squaredNorm() == 0) continue;
      rim.points.emplace_back(q.x, q.y);
      rim.normals.push_back(n.normalized());
    }
  };
  add(silhouette);
  for (const auto& h : silhouette.holes) add(h);
  return rim;
}

namespace {

// A view's rim points bucketed in square cells of the image, for the nearest one within a radius.
class RimLookup {
 public:
  static constexpr double kCell = 16;  // pixels
  explicit RimLookup(const SilhouetteRim& rim) : rim(rim), projection(rim.camera.projection()), eye(rim.camera.centre_in_world()) {
    for (std::size_t i = 0; i < rim.points.size(); ++i) cells_[key(cell(rim.points[i]))].push_back(i);
  }
  // The index of the rim point nearest q within radius pixels, or -1.
  long nearest(const Eigen::Vector2d& q, double radius) const {
    // Off the image by more than the radius (a point near the camera's plane projects far out):
    // no rim point can be near, and the cell's index would overflow.
    radius = std::min(radius, double(rim.camera.width + rim.camera.height));
    if (!(q.x() >= -radius && q.y() >= -radius && q.x() <= rim.camera.width + radius && q.y() <= rim.camera.height + radius))
      return -1;
    const Eigen::Vector2i c = cell(q);
    const int reach = static_cast<int>(std::ceil(radius / kCell));
    long best = -1;
    double best_d2 = radius * radius;
    for (int dx = -reach; dx <= reach; ++dx)
      for (int dy = -reach; dy <= reach; ++dy) {
        const auto it = cells_.find(key(c + Eigen::Vector2i(dx, dy)));
        if (it == cells_.end()) continue;
        for (std::size_t j : it->second)
          if (const double d2 = (rim.points[j] - q).squaredNorm(); d2 <= best_d2) best_d2 = d2, best = static_cast<long>(j);
      }
    return best;
  }

  const SilhouetteRim& rim;
  const Eigen::Matrix<double, 3, 4> projection;
  const Eigen::Vector3d eye;

 private:
  static Eigen::Vector2i cell(const Eigen::Vector2d& q) { return (q / kCell).array().floor().cast<int>(); }
  static std::uint64_t key(const Eigen::Vector2i& c) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.x())) << 32) | static_cast<std::uint32_t>(c.y());
  }
  std::unordered_map<std::uint64_t, std::vector<std::size_t>> cells_;
};

}  // namespace

void mark_unobserved(std::span<SurfaceSample> samples, std::span<const SilhouetteRim> views, double tolerance, double rim_deg,
                     double separation_deg) {
  if (!(rim_deg > 0 && rim_deg < 90) || !(separation_deg > 0 && separation_deg < 90))
    throw std::invalid_argument("model surface: rim_deg and separation_deg must be in (0, 90) degrees, found " +
                                std::to_string(rim_deg) + " and " + std::to_string(separation_deg));
  if (!(tolerance >= 0)) throw std::invalid_argument("model surface: the rim tolerance must be >= 0 metres, found " + std::to_string(tolerance));
  constexpr double kDeg = std::numbers::pi / 180;
  const double sin_rim = std::sin(rim_deg * kDeg), cos_rim = std::cos(rim_deg * kDeg), cos_separation = std::cos(separation_deg * kDeg);
  std::vector<RimLookup> lookups;
  lookups.reserve(views.size());
  for (const auto& v : views) lookups.emplace_back(v);
  struct Rim {
    Eigen::Vector3d sight, cone_normal;  // the line of sight (unit, eye to sample); the cone of sight's outward normal there
  };
  std::vector<Rim> rims;
  for (auto& s : samples) {
    rims.clear();
    const Eigen::Vector3d n = s.normal.normalized();
    for (const auto& v : lookups) {
      const Eigen::Vector3d d = (s.position - v.eye).normalized();
      if (std::abs(d.dot(n)) > sin_rim) continue;
      const Eigen::Vector3d h = v.projection * s.position.homogeneous();
      if (!(h.z() > 0)) continue;
      const double radius_px = v.rim.camera.K(0, 0) * tolerance / h.z() + 1;
      if (const long k = v.nearest(h.hnormalized(), radius_px); k >= 0) rims.push_back({d, v.rim.normals[static_cast<std::size_t>(k)]});
    }
    bool pinned = false;
    for (std::size_t i = 0; i < rims.size() && !pinned; ++i)
      for (std::size_t j = i + 1; j < rims.size() && !pinned; ++j)
        pinned = std::abs(rims[i].sight.dot(rims[j].sight)) <= cos_separation && rims[i].cone_normal.dot(rims[j].cone_normal) >= cos_rim;
    s.unpinned = !pinned;
  }
}

}  // namespace fba::grasp
