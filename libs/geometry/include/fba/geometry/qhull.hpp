// One run of qhull (the reentrant qhull_r) on a set of points: the run's memory and its message
// stream are handled here, and the caller reads the hull qhull built while it stands.
#pragma once

#include <functional>
#include <span>
#include <string>

struct qhT;  // qhull_r's state; a reader includes <libqhull_r/qhull_ra.h> to walk its facets and vertices

namespace fba::geometry {

// How a qhull run ended: its exit code (0: the hull was built) and what qhull wrote on failure.
struct QhullStatus {
  int code = 0;
  std::string message;
};

// Runs qhull with `options` (as on its command line, e.g. "qhull Qt") on the points in `coords`,
// `dim` coordinates each, one point after another. When the hull is built, `read` is called with
// qhull's state before that is freed.
QhullStatus run_qhull(int dim, std::span<double> coords, const std::string& options,
                      const std::function<void(qhT*)>& read);

}  // namespace fba::geometry
