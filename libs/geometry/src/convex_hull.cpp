#include "fba/geometry/convex_hull.hpp"

#include <algorithm>
#include <string>

#include <libqhull_r/qhull_ra.h>

#include "fba/geometry/qhull.hpp"

namespace fba::geometry {

ConvexHull convex_hull(const TriangleMesh& mesh) {
  if (mesh.vertices.size() < 4)
    throw ConvexHullError("convex hull: a solid needs at least 4 vertices, found " + std::to_string(mesh.vertices.size()));
  std::vector<coordT> coords;
  coords.reserve(3 * mesh.vertices.size());
  for (const auto& v : mesh.vertices) coords.insert(coords.end(), {v.x(), v.y(), v.z()});
  ConvexHull hull;
  const QhullStatus status = run_qhull(3, coords, "qhull Qt", [&](qhT* qh) {  // Qt: triangulated facets, for the volume
    qh_getarea(qh, qh->facet_list);
    hull.volume = qh->totvol;
    vertexT* vertex;
    FORALLvertices hull.vertices.emplace_back(vertex->point[0], vertex->point[1], vertex->point[2]);
  });
  if (status.code != 0)
    throw ConvexHullError("convex hull: the mesh's vertices span no volume (qhull: " + status.message + ")");
  return hull;
}

std::vector<Eigen::Vector2d> convex_hull_2d(std::vector<Eigen::Vector2d> p) {
  std::sort(p.begin(), p.end(), [](const auto& a, const auto& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  p.erase(std::unique(p.begin(), p.end()), p.end());
  if (p.size() < 3) return p;
  const auto turn = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
  };
  std::vector<Eigen::Vector2d> hull(2 * p.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {  // the lower chain, left to right
    while (k >= 2 && turn(hull[k - 2], hull[k - 1], p[i]) <= 0) --k;
    hull[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, lower = k + 1; i-- > 0;) {  // the upper chain, right to left
    while (k >= lower && turn(hull[k - 2], hull[k - 1], p[i]) <= 0) --k;
    hull[k++] = p[i];
  }
  hull.resize(k - 1);  // the last point is the first
  return hull;
}

}  // namespace fba::geometry
