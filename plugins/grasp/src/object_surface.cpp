#include "fba/grasp/object_surface.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <random>
#include <string>

#include <Eigen/Geometry>

#include "fba/grasp/angles.hpp"

namespace fba::grasp {
namespace {

// The closest point of triangle abc to p (Ericson, Real-Time Collision Detection, 5.1.5).
Eigen::Vector3d closest_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                    const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

// Line parameter t of the hit of o + t d with triangle abc (Moller-Trumbore), both directions.
std::optional<double> line_hit(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& a,
                               const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d e1 = b - a, e2 = c - a;
  const Eigen::Vector3d h = d.cross(e2);
  const double det = e1.dot(h);
  if (std::abs(det) < 1e-18) return std::nullopt;  // parallel to the triangle's plane
  const double inv = 1.0 / det;
  const Eigen::Vector3d s = o - a;
  const double u = inv * s.dot(h);
  if (u < 0 || u > 1) return std::nullopt;
  const Eigen::Vector3d q = s.cross(e1);
  const double v = inv * d.dot(q);
  if (v < 0 || u + v > 1) return std::nullopt;
  return inv * e2.dot(q);
}

}  // namespace

ObjectSurface::ObjectSurface(const TriangleMesh& mesh) {
  if (mesh.triangles.empty()) throw std::invalid_argument("object surface: the mesh has no triangles");
  const int n = static_cast<int>(mesh.vertices.size());
  double six_volume = 0;
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();  // 24 * first moment of volume
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    const auto& t = mesh.triangles[i];
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || t[k] >= n)
        throw std::invalid_argument("object surface: triangle " + std::to_string(i) + " refers to vertex " +
                                    std::to_string(t[k]) + ", expected 0.." + std::to_string(n - 1));
    const Eigen::Vector3d a = mesh.vertices[t[0]].cast<double>(), b = mesh.vertices[t[1]].cast<double>(),
                          c = mesh.vertices[t[2]].cast<double>();
    const Eigen::Vector3d cross = (b - a).cross(c - a);
    const double twice_area = cross.norm();
    if (!(twice_area > 0)) continue;  // a sliver carries no surface and no normal
    // Signed tetrahedron (origin, a, b, c): volume a.(b x c) / 6, centroid (a + b + c) / 4.
    const double v6 = a.dot(b.cross(c));
    six_volume += v6;
    moment += v6 * (a + b + c);
    triangles_.push_back({a, b, c});
    inward_.push_back(-cross / twice_area);
    area_total_ += twice_area / 2;
    cumulative_area_.push_back(area_total_);
  }
  volume_ = six_volume / 6.0;
  const Eigen::AlignedBox3d box = [&] {
    Eigen::AlignedBox3d b;
    for (const auto& t : triangles_)
      for (const auto& p : t) b.extend(p);
    return b;
  }();
  // An open mesh gives a volume that depends on the origin; a closed one much larger than zero.
  if (triangles_.empty() || !(std::abs(volume_) > 1e-9 * box.sizes().prod()))
    throw std::invalid_argument("object surface: the mesh encloses no volume (expected a closed surface, found "
                                "volume " + std::to_string(volume_) + " m^3)");
  com_ = moment / (4.0 * six_volume);
  if (volume_ < 0) {  // clockwise triangles: the normals computed above point outward
    for (auto& nrm : inward_) nrm = -nrm;
    volume_ = -volume_;
  }
  for (const auto& t : triangles_)
    for (const auto& p : t) r_max_ = std::max(r_max_, (p - com_).norm());
}

GraspContact ObjectSurface::on_triangle(std::size_t t, double u, double v) const {
  const auto& tri = triangles_[t];
  return {tri[0] + u * (tri[1] - tri[0]) + v * (tri[2] - tri[0]), inward_[t]};
}

GraspContact ObjectSurface::closest_point(const Eigen::Vector3d& p) const {
  double best = std::numeric_limits<double>::infinity();
  GraspContact result;
  for (std::size_t t = 0; t < triangles_.size(); ++t) {
    const Eigen::Vector3d q = closest_on_triangle(p, triangles_[t][0], triangles_[t][1], triangles_[t][2]);
    const double d = (q - p).squaredNorm();
    if (d < best) {
      best = d;
      result = {q, inward_[t]};
    }
  }
  return result;
}

ObjectSurface::Placement ObjectSurface::place(const GraspContact& approximate) const {
  if (!approximate.position.allFinite())
    throw std::invalid_argument("object surface: a contact position is not finite");
  Placement out;
  const bool has_normal = approximate.normal.allFinite() && approximate.normal.norm() > 0;
  double best = std::numeric_limits<double>::infinity();
  if (has_normal) {
    const Eigen::Vector3d d = approximate.normal.normalized();
    for (std::size_t t = 0; t < triangles_.size(); ++t) {
      const auto hit = line_hit(approximate.position, d, triangles_[t][0], triangles_[t][1], triangles_[t][2]);
      if (hit && std::abs(*hit) < best) {
        best = std::abs(*hit);
        out.contact = {approximate.position + *hit * d, inward_[t]};
      }
    }
  }
  if (!std::isfinite(best)) return place_closest(approximate);
  out.displacement = best;
  if (has_normal) out.normal_error_deg = angle_between_deg(approximate.normal, out.contact.normal);
  return out;
}

ObjectSurface::Placement ObjectSurface::place_closest(const GraspContact& approximate) const {
  if (!approximate.position.allFinite())
    throw std::invalid_argument("object surface: a contact position is not finite");
  Placement out;
  out.contact = closest_point(approximate.position);
  out.displacement = (out.contact.position - approximate.position).norm();
  out.along_normal = false;
  if (approximate.normal.allFinite() && approximate.normal.norm() > 0)
    out.normal_error_deg = angle_between_deg(approximate.normal, out.contact.normal);
  return out;
}

const PlacedGrasp& GraspOnSurface::worse() const {
  if (along_normal.quality.force_closure != closest.quality.force_closure)
    return along_normal.quality.force_closure ? closest : along_normal;
  return closest.quality.epsilon < along_normal.quality.epsilon ? closest : along_normal;
}

GraspOnSurface place_grasp(const ObjectSurface& surface, const std::array<GraspContact, 3>& contacts,
                           const QualityParams& params) {
  const auto placed = [&](auto place) {
    PlacedGrasp g;
    std::array<GraspContact, 3> at;
    for (int k = 0; k < 3; ++k) {
      g.contacts[k] = (surface.*place)(contacts[k]);
      at[k] = g.contacts[k].contact;
    }
    // Two contacts placed on one point (snapped to the same corner; the measure's own rule) hold
    // nothing it can define: not force closure. Other bad input (friction, cone edges) is thrown.
    for (int i = 0; i < 3; ++i)
      for (int j = i + 1; j < 3; ++j)
        if ((at[i].position - at[j].position).norm() <= 1e-9 * surface.r_max())
          g.degenerate = "contacts " + std::to_string(i) + " and " + std::to_string(j) + " placed on one point";
    if (g.degenerate.empty()) g.quality = surface.evaluate(at, params);
    return g;
  };
  return {placed(&ObjectSurface::place), placed(&ObjectSurface::place_closest)};
}

SurfaceSampling sample_for_synthesis(const ObjectSurface& surface, std::size_t count, std::uint64_t seed) {
  if (count < 3) throw std::invalid_argument("surface sampling: expected at least 3 samples, found " + std::to_string(count));
  std::mt19937_64 rng(seed);
  SurfaceSampling out;
  out.neighbour_radius = 2.5 * std::sqrt(surface.area() / static_cast<double>(count));
  out.samples.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    const GraspContact c = surface.sample(rng);
    out.samples.push_back({c.position, -c.normal});
  }
  estimate_curvature(out.samples, out.neighbour_radius);
  return out;
}

double quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  const double pos = std::clamp(q, 0.0, 1.0) * (values.size() - 1);
  const std::size_t lo = static_cast<std::size_t>(pos);
  const std::size_t hi = std::min(lo + 1, values.size() - 1);
  return values[lo] + (pos - lo) * (values[hi] - values[lo]);
}

RandomBaseline random_baseline(const ObjectSurface& surface, std::size_t sets, std::uint64_t seed,
                               const QualityParams& params) {
  std::mt19937_64 rng(seed);
  std::vector<double> eps, eps_fc;
  eps.reserve(sets);
  std::size_t fc = 0;
  for (std::size_t i = 0; i < sets; ++i) {
    const std::array<GraspContact, 3> c = {surface.sample(rng), surface.sample(rng), surface.sample(rng)};
    const GraspQuality q = surface.evaluate(c, params);
    eps.push_back(q.epsilon);
    if (q.force_closure) {
      ++fc;
      eps_fc.push_back(q.epsilon);
    }
  }
  RandomBaseline r;
  r.sets = sets;
  r.force_closure_share = sets ? static_cast<double>(fc) / sets : 0.0;
  r.epsilon_p99 = quantile(eps, 0.99);
  r.epsilon_median_fc = quantile(eps_fc, 0.5);
  return r;
}

}  // namespace fba::grasp
