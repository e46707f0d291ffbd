#include "fba/grasp/model_surface.hpp"

#include "neighbour_grid.hpp"
#include "parallel.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <unordered_map>

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
  // The walk's own cell: its centre from the lattice, not summed level by level (which differs in
  // the last bit, and a probe on a boundary can then fall on the other side).
  return model.cell(c.depth, lattice.x(), lattice.y(), lattice.z(), *c.node);
}

// An occupied leaf's neighbours just beyond its six faces: the leaf at each face's centre (as
// large as the leaf or larger, it covers the whole face) or, when that one is finer, the leaves at
// the face's four quarter points. Each by its index among the model's occupied leaves; -1 for an
// empty leaf or outside the root box.
struct FaceNeighbours {
  struct Probe {
    std::int8_t axis, sign, quarters;  // quarters: the share of the face it covers, in fourths
    std::int32_t leaf;
  };
  std::array<Probe, 24> probes;
  int count = 0;
  std::array<std::int32_t, 6> centre;  // the leaf at each face's centre (2 * axis + (sign > 0))
};

// The occupied leaves in the model's walk order, and each one's index by its node.
struct OccupiedLeaves {
  std::vector<OctreeCell> cells;
  std::unordered_map<const OctreeNode*, std::int32_t> index;
  std::int32_t at(const OctreeCell& c) const {
    if (!c.node || !c.occupied()) return -1;
    return index.at(c.node);
  }
};

FaceNeighbours face_neighbours(const Octree& model, const OccupiedLeaves& leaves, const OctreeCell& c) {
  FaceNeighbours out;
  const double h = c.half_size, eps = 1e-3 * h;
  for (int a = 0; a < 3; ++a) {
    const int u = (a + 1) % 3, v = (a + 2) % 3;
    for (int sign : {-1, 1}) {
      Eigen::Vector3d centre = c.centre;
      centre[a] += sign * (h + eps);
      const OctreeCell n = leaf_at(model, centre);
      out.centre[2 * a + (sign > 0)] = leaves.at(n);
      if (!n.node || n.depth <= c.depth) {
        out.probes[out.count++] = {std::int8_t(a), std::int8_t(sign), 4, leaves.at(n)};
        continue;
      }
      for (int qu : {-1, 1})
        for (int qv : {-1, 1}) {
          Eigen::Vector3d p = centre;
          p[u] += qu * h / 2;
          p[v] += qv * h / 2;
          out.probes[out.count++] = {std::int8_t(a), std::int8_t(sign), 1, leaves.at(leaf_at(model, p))};
        }
    }
  }
  return out;
}

// The occupied leaves in the model's walk order.
OccupiedLeaves occupied_leaves(const Octree& model) {
  OccupiedLeaves leaves;
  model.for_each_occupied_leaf([&](const OctreeCell& c) {
    leaves.index.emplace(c.node, std::int32_t(leaves.cells.size()));
    leaves.cells.push_back(c);
  });
  return leaves;
}

// The object, with a table: the occupied leaves joined through shared faces to one that stands
// on it. A pillar the views could not carve stays joined; space above the object that no view saw
// (carving keeps it: nothing there was seen to be empty), cut off from the object by carved space
// centimetres above the table, does not. A leaf stands on the table when its bottom lies within
// one of its edges of it: an object that touches the table on a small patch or a point (a sphere,
// an ellipsoid) has only a leaf or two there, and the carver judges a leaf by its centre, which
// beside such a contact lies outside the object (under a sphere's lowest point), so the leaf that
// straddles the table is carved and the object's lowest leaf stands up to an edge above it.
// Without a table, every occupied leaf. 1 for a leaf of the object, by leaf index.
std::vector<char> object_leaves(const OccupiedLeaves& leaves, const std::vector<FaceNeighbours>& neighbours,
                                std::optional<double> table_z) {
  std::vector<char> object(leaves.cells.size(), table_z ? 0 : 1);
  if (!table_z) return object;
  std::vector<std::int32_t> queue;
  for (std::size_t i = 0; i < leaves.cells.size(); ++i) {
    const OctreeCell& c = leaves.cells[i];
    if (c.centre.z() - 3 * c.half_size <= *table_z) object[i] = 1, queue.push_back(std::int32_t(i));
  }
  while (!queue.empty()) {
    const FaceNeighbours& f = neighbours[std::size_t(queue.back())];
    queue.pop_back();
    for (int k = 0; k < f.count; ++k)
      if (const std::int32_t j = f.probes[std::size_t(k)].leaf; j >= 0 && !object[std::size_t(j)])
        object[std::size_t(j)] = 1, queue.push_back(j);
  }
  return object;
}

// A surface leaf before the fit: where the surface is and which way its free faces point.
struct Raw {
  Eigen::Vector3d position, free_direction;
  bool uncertain;
};

// An object leaf, if it is on the surface.
std::optional<Raw> examine_leaf(const Octree& model, const ModelSurfaceParams& params, const OctreeCell& c,
                                const FaceNeighbours& f, const std::vector<char>& object) {
  auto is_object = [&](std::int32_t leaf) { return leaf >= 0 && object[std::size_t(leaf)]; };
  Eigen::Vector3d free_direction = Eigen::Vector3d::Zero();  // towards the faces no object leaf is beyond
  for (int k = 0; k < f.count; ++k) {
    const auto& probe = f.probes[std::size_t(k)];
    if (!is_object(probe.leaf)) free_direction[probe.axis] += probe.sign * probe.quarters / 4.0;
  }
  bool any_free = false;
  for (int a = 0; a < 3; ++a) any_free = any_free || free_direction[a] != 0;
  // Faces free on both sides of an axis cancel there (a wall one leaf thick): such a leaf is
  // surface too, its direction left to the neighbours' fit.
  if (!any_free) {
    bool two_sided = false;
    for (int a = 0; a < 3 && !two_sided; ++a) two_sided = !is_object(f.centre[2 * a]) && !is_object(f.centre[2 * a + 1]);
    if (!two_sided) return std::nullopt;
  }
  const Eigen::Vector3d position = c.centre + c.half_size * free_direction.cwiseMax(-1.0).cwiseMin(1.0);
  if (params.table_z && position.z() < *params.table_z) return std::nullopt;  // the model's cone below the table
  return Raw{position, free_direction, c.state() == NodeState::Partial && c.depth < model.max_depth};
}

// A surface sample from its raw leaf and its neighbours': the normal of the plane fitted to them
// (or, failing a fit, the free direction), and the position moved onto that plane.
SurfaceSample fit_sample(const Octree& model, const std::vector<Raw>& raw, const std::vector<SurfaceSample>& s,
                         const std::vector<std::size_t>& nb, std::size_t i, double radius) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero(), direction = Eigen::Vector3d::Zero();
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
    if (eig.eigenvalues()[1] > 1e-12 * radius * radius) {
      normal = eig.eigenvectors().col(0);
      if (normal.dot(direction) < 0) normal = -normal;
      if (direction.squaredNorm() == 0) normal = Eigen::Vector3d::Zero();
    }
  }
  if (normal.squaredNorm() == 0) normal = raw[i].free_direction;
  if (normal.squaredNorm() == 0) normal = s[i].position - model.bounds.center();  // a lone voxel: away from the centre
  if (normal.squaredNorm() == 0) normal = Eigen::Vector3d::UnitZ();
  normal.normalize();
  SurfaceSample out = s[i];
  out.normal = normal;
  // Onto the fitted plane: removes the voxel staircase that would read as curvature.
  out.position = s[i].position + (mean - s[i].position).dot(normal) * normal;
  return out;
}

// The raw surface leaves as samples with fitted normals, each against its neighbours within `radius`.
std::vector<SurfaceSample> fit_samples(const Octree& model, const std::vector<Raw>& raw, double radius,
                                       const ParallelFor& parallel_for) {
  std::vector<SurfaceSample> s(raw.size());
  for (std::size_t i = 0; i < raw.size(); ++i) s[i].position = raw[i].position, s[i].uncertain = raw[i].uncertain;
  const std::vector<std::vector<std::size_t>> neighbourhoods = NeighbourGrid(s, radius).neighbourhoods(true, parallel_for);
  std::vector<SurfaceSample> smoothed = s;
  for_each_chunk(parallel_for, s.size(), [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) smoothed[i] = fit_sample(model, raw, s, neighbourhoods[i], i, radius);
  });
  return smoothed;
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
  // The neighbours are found once per leaf, at once with a parallel_for.
  const OccupiedLeaves leaves = occupied_leaves(model);
  out.leaves = leaves.cells.size();
  std::vector<FaceNeighbours> neighbours(leaves.cells.size());
  for_each_chunk(params.parallel_for, leaves.cells.size(), [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) neighbours[i] = face_neighbours(model, leaves, leaves.cells[i]);
  });
  const std::vector<char> object = object_leaves(leaves, neighbours, params.table_z);
  const std::size_t objects = std::size_t(std::count(object.begin(), object.end(), 1));
  out.unsupported_leaves = leaves.cells.size() - objects;

  // Each leaf on its own (at once with a parallel_for), kept in the walk's order.
  std::vector<std::optional<Raw>> surface_leaf(leaves.cells.size());
  for_each_chunk(params.parallel_for, leaves.cells.size(), [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      if (object[i]) surface_leaf[i] = examine_leaf(model, params, leaves.cells[i], neighbours[i], object);
  });
  // The finest depth among the object's leaves, surface or not.
  int finest_depth = -1;
  for (std::size_t i = 0; i < leaves.cells.size(); ++i)
    if (object[i]) finest_depth = std::max(finest_depth, leaves.cells[i].depth);
  std::vector<Raw> raw;
  for (auto& r : surface_leaf)
    if (r) raw.push_back(*r);
  if (raw.empty()) return out;
  out.finest_edge = size.x() / double(std::int64_t(1) << finest_depth);
  out.radius = params.radius > 0 ? params.radius : 3 * out.finest_edge;
  out.samples = fit_samples(model, raw, out.radius, params.parallel_for);
  estimate_curvature(out.samples, out.radius, params.parallel_for);
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
