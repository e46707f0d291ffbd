#include "fba/geometry/qhull.hpp"

#include <cstdio>
#include <cstdlib>
#include <vector>

#include <libqhull_r/qhull_ra.h>

namespace fba::geometry {

QhullStatus run_qhull(int dim, std::span<double> coords, const std::string& options,
                      const std::function<void(qhT*)>& read) {
  static_assert(sizeof(coordT) == sizeof(double), "qhull_r built with double coordinates");
  char* err_text = nullptr;
  std::size_t err_size = 0;
  FILE* err = open_memstream(&err_text, &err_size);
  qhT qh_storage;
  qhT* qh = &qh_storage;
  qh_zero(qh, err);
  std::vector<char> command(options.begin(), options.end());  // qhull takes its options writable
  command.push_back('\0');
  const int points = static_cast<int>(coords.size() / dim);
  const int code = qh_new_qhull(qh, dim, points, coords.data(), False, command.data(), nullptr, err);
  if (code == 0) read(qh);
  qh_freeqhull(qh, !qh_ALL);
  int curlong = 0, totlong = 0;
  qh_memfreeshort(qh, &curlong, &totlong);
  std::fclose(err);
  QhullStatus status{code, err_text ? err_text : ""};
  std::free(err_text);
  return status;
}

}  // namespace fba::geometry
