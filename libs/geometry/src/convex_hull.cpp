#include "fba/geometry/convex_hull.hpp"

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

}  // namespace fba::geometry
