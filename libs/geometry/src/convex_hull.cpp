#include "fba/geometry/convex_hull.hpp"

#include <cstdio>
#include <cstdlib>
#include <string>

#include <libqhull_r/qhull_ra.h>

namespace fba::geometry {

ConvexHull convex_hull(const TriangleMesh& mesh) {
  if (mesh.vertices.size() < 4)
    throw ConvexHullError("convex hull: a solid needs at least 4 vertices, found " + std::to_string(mesh.vertices.size()));
  std::vector<coordT> coords;
  coords.reserve(3 * mesh.vertices.size());
  for (const auto& v : mesh.vertices) coords.insert(coords.end(), {v.x(), v.y(), v.z()});
  char* err_text = nullptr;
  std::size_t err_size = 0;
  FILE* err = open_memstream(&err_text, &err_size);
  qhT qh_storage;
  qhT* qh = &qh_storage;
  qh_zero(qh, err);
  char options[] = "qhull Qt";  // triangulated facets, for the volume
  const int code = qh_new_qhull(qh, 3, static_cast<int>(mesh.vertices.size()), coords.data(), False, options, nullptr, err);
  ConvexHull hull;
  if (code == 0) {
    qh_getarea(qh, qh->facet_list);
    hull.volume = qh->totvol;
    vertexT* vertex;
    FORALLvertices hull.vertices.emplace_back(vertex->point[0], vertex->point[1], vertex->point[2]);
  }
  qh_freeqhull(qh, !qh_ALL);
  int curlong = 0, totlong = 0;
  qh_memfreeshort(qh, &curlong, &totlong);
  std::fclose(err);
  const std::string message(err_text ? err_text : "");
  std::free(err_text);
  if (code != 0) throw ConvexHullError("convex hull: the mesh's vertices span no volume (qhull: " + message + ")");
  return hull;
}

}  // namespace fba::geometry
