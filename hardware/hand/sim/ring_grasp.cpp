#include "ring_grasp.hpp"

#include <cmath>
#include <optional>
#include <string>

#include <Eigen/Geometry>

namespace fba::sim_hand {

namespace {

struct Hit {
  double t = 0;
  Eigen::Vector3d normal;  // the triangle's, unit
};

// The farthest crossing of the ray origin + t dir (t > 0) with the mesh (Moller-Trumbore).
std::optional<Hit> last_hit(const TriangleMesh& mesh, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir) {
  std::optional<Hit> best;
  for (const auto& tri : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices[static_cast<std::size_t>(tri[0])].cast<double>();
    const Eigen::Vector3d e1 = mesh.vertices[static_cast<std::size_t>(tri[1])].cast<double>() - a;
    const Eigen::Vector3d e2 = mesh.vertices[static_cast<std::size_t>(tri[2])].cast<double>() - a;
    const Eigen::Vector3d p = dir.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-15) continue;
    const Eigen::Vector3d s = origin - a;
    const double u = s.dot(p) / det;
    if (u < 0 || u > 1) continue;
    const Eigen::Vector3d q = s.cross(e1);
    const double v = dir.dot(q) / det;
    if (v < 0 || u + v > 1) continue;
    const double t = e2.dot(q) / det;
    if (t <= 0 || (best && t <= best->t)) continue;
    const Eigen::Vector3d n = e1.cross(e2);
    if (n.norm() == 0) continue;
    best = Hit{t, n.normalized()};
  }
  return best;
}

}  // namespace

Grasp ring_grasp(const TriangleMesh& mesh, double height, double thumb_angle, double clearance) {
  Eigen::AlignedBox3d box;
  for (const auto& v : mesh.vertices) box.extend(v.cast<double>());
  const Eigen::Vector3d origin(box.center().x(), box.center().y(), height);
  Grasp g;
  for (int i = 0; i < 3; ++i) {
    const double angle = thumb_angle + i * 2 * M_PI / 3;
    const Eigen::Vector3d dir(std::cos(angle), std::sin(angle), 0);
    const auto hit = last_hit(mesh, origin, dir);
    if (!hit)
      throw std::invalid_argument("ring grasp: a ray at height " + std::to_string(height) + " m misses the mesh (its z spans " +
                                  std::to_string(box.min().z()) + " .. " + std::to_string(box.max().z()) + " m)");
    auto& c = g.contacts[static_cast<std::size_t>(i)];
    c.position = origin + hit->t * dir;
    c.normal = hit->normal.dot(dir) > 0 ? -hit->normal : hit->normal;
  }
  g.approach = -Eigen::Vector3d::UnitZ();
  g.spread = (g.contacts[1].position - g.contacts[2].position).norm();
  const Eigen::Vector3d mid = (g.contacts[1].position + g.contacts[2].position) / 2;
  g.aperture = (mid - g.contacts[0].position).norm() + 2 * clearance;
  return g;
}

}  // namespace fba::sim_hand
