#include "fba/geometry/voxelize.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace fba::geometry {

std::size_t VoxelGrid::count() const {
  return static_cast<std::size_t>(std::count_if(occupancy.begin(), occupancy.end(),
                                                [](std::uint8_t v) { return v != 0; }));
}

double VoxelGrid::occupied_volume() const {
  const double h = voxel_size();
  return static_cast<double>(count()) * h * h * h;
}

bool VoxelGrid::same_layout(const VoxelGrid& other) const {
  if (n != other.n) return false;
  // Bounds computed along different routes may differ in the last bits; a hundredth of a voxel
  // is far below anything that would shift a voxel.
  const double tol = 0.01 * voxel_size();
  return (bounds.min() - other.bounds.min()).cwiseAbs().maxCoeff() <= tol &&
         (bounds.max() - other.bounds.max()).cwiseAbs().maxCoeff() <= tol;
}

namespace {

// 2D orientation of x against the directed edge p->q, evaluated in one canonical vertex order so
// that the two triangles sharing an edge get exactly opposite values (bit for bit). That makes
// the zero test and the tie rule below consistent between neighbours.
double edge_function(const Eigen::Vector2d& p, const Eigen::Vector2d& q, const Eigen::Vector2d& x) {
  const bool swap = (q.x() < p.x()) || (q.x() == p.x() && q.y() < p.y());
  const Eigen::Vector2d& a = swap ? q : p;
  const Eigen::Vector2d& b = swap ? p : q;
  const double e = (b.x() - a.x()) * (x.y() - a.y()) - (b.y() - a.y()) * (x.x() - a.x());
  return swap ? -e : e;
}

// The tie rule for a point exactly on an edge: of the two opposite directions an edge has in its
// two triangles (after orienting both counter-clockwise), exactly one is accepted.
bool owns_edge(const Eigen::Vector2d& direction) {
  return direction.y() > 0 || (direction.y() == 0 && direction.x() < 0);
}

// Adds one inside-vote per voxel from rays parallel to `axis` through the voxel centres.
void vote_along_axis(const TriangleMesh& mesh, const Eigen::AlignedBox3d& cube, int n, int axis,
                     std::vector<std::uint8_t>& votes) {
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  const double h = cube.sizes().x() / n;
  const Eigen::Vector3d origin = cube.min();
  // Crossing coordinates along `axis` for every column (iu, iv).
  std::vector<std::vector<double>> columns(static_cast<std::size_t>(n) * n);

  for (const auto& t : mesh.triangles) {
    Eigen::Vector3d p3[3];
    Eigen::Vector2d p[3];
    for (int k = 0; k < 3; ++k) {
      p3[k] = mesh.vertices[t[k]].cast<double>();
      p[k] = Eigen::Vector2d(p3[k][u], p3[k][v]);
    }
    const double area = (p[1].x() - p[0].x()) * (p[2].y() - p[0].y()) -
                        (p[1].y() - p[0].y()) * (p[2].x() - p[0].x());
    if (area == 0) continue;  // parallel to the rays: its neighbours carry the crossing
    const double sign = area > 0 ? 1.0 : -1.0;
    const double lo_u = std::min({p[0].x(), p[1].x(), p[2].x()});
    const double hi_u = std::max({p[0].x(), p[1].x(), p[2].x()});
    const double lo_v = std::min({p[0].y(), p[1].y(), p[2].y()});
    const double hi_v = std::max({p[0].y(), p[1].y(), p[2].y()});
    // Columns whose centre line (origin + (i + 0.5) h) falls within the footprint.
    const int iu0 = std::max(0, static_cast<int>(std::ceil((lo_u - origin[u]) / h - 0.5)));
    const int iu1 = std::min(n - 1, static_cast<int>(std::floor((hi_u - origin[u]) / h - 0.5)));
    const int iv0 = std::max(0, static_cast<int>(std::ceil((lo_v - origin[v]) / h - 0.5)));
    const int iv1 = std::min(n - 1, static_cast<int>(std::floor((hi_v - origin[v]) / h - 0.5)));
    for (int iv = iv0; iv <= iv1; ++iv) {
      for (int iu = iu0; iu <= iu1; ++iu) {
        const Eigen::Vector2d x(origin[u] + (iu + 0.5) * h, origin[v] + (iv + 0.5) * h);
        double w[3];
        bool inside = true;
        for (int k = 0; k < 3 && inside; ++k) {
          const Eigen::Vector2d& a = p[(k + 1) % 3];
          const Eigen::Vector2d& b = p[(k + 2) % 3];
          const double e = sign * edge_function(a, b, x);  // weight of vertex k (opposite edge)
          if (e < 0 || (e == 0 && !owns_edge(sign * (b - a)))) inside = false;
          w[k] = e;
        }
        if (!inside) continue;
        const double sum = w[0] + w[1] + w[2];
        const double hit = (w[0] * p3[0][axis] + w[1] * p3[1][axis] + w[2] * p3[2][axis]) / sum;
        columns[static_cast<std::size_t>(iv) * n + iu].push_back(hit);
      }
    }
  }

  for (int iv = 0; iv < n; ++iv) {
    for (int iu = 0; iu < n; ++iu) {
      auto& hits = columns[static_cast<std::size_t>(iv) * n + iu];
      if (hits.empty()) continue;
      std::sort(hits.begin(), hits.end());
      std::size_t passed = 0;
      for (int ia = 0; ia < n; ++ia) {
        const double c = origin[axis] + (ia + 0.5) * h;
        while (passed < hits.size() && hits[passed] < c) ++passed;
        if (passed % 2 == 1) {
          int ijk[3];
          ijk[axis] = ia;
          ijk[u] = iu;
          ijk[v] = iv;
          ++votes[(static_cast<std::size_t>(ijk[2]) * n + ijk[1]) * n + ijk[0]];
        }
      }
    }
  }
}

void check_cube(const Eigen::AlignedBox3d& cube, const char* who) {
  const Eigen::Vector3d s = cube.sizes();
  if (cube.isEmpty() || !(s.x() > 0) ||
      std::abs(s.x() - s.y()) > 1e-9 * s.x() || std::abs(s.x() - s.z()) > 1e-9 * s.x())
    throw std::invalid_argument(std::string(who) + ": bounds must be a non-empty cube");
}

}  // namespace

VoxelGrid voxelize(const TriangleMesh& mesh, const Eigen::AlignedBox3d& cube, int depth,
                   std::optional<double> z_min) {
  check_cube(cube, "voxelize");
  if (depth < 0 || depth > 10) throw std::invalid_argument("voxelize: depth must be in 0..10");
  const int n = 1 << depth;
  VoxelGrid grid(cube, n);
  std::vector<std::uint8_t> votes(grid.occupancy.size(), 0);
  for (int axis = 0; axis < 3; ++axis) vote_along_axis(mesh, cube, n, axis, votes);
  for (std::size_t i = 0; i < votes.size(); ++i) grid.occupancy[i] = votes[i] >= 2 ? 1 : 0;
  if (z_min) clip_below(grid, *z_min);
  return grid;
}

VoxelGrid voxelize_lattice_surface(const TriangleMesh& mesh, const Eigen::AlignedBox3d& cube,
                                   int depth) {
  check_cube(cube, "voxelize_lattice_surface");
  if (depth < 0 || depth > 10)
    throw std::invalid_argument("voxelize_lattice_surface: depth must be in 0..10");
  const int n = 1 << depth;
  VoxelGrid grid(cube, n);
  const double h = grid.voxel_size();
  // wall[axis] at (i, j, k): the face between voxel (i,j,k) - e_axis and (i,j,k), for lattice
  // plane index 0..n along `axis` (0 and n are the grid's border).
  const std::size_t planes = static_cast<std::size_t>(n + 1) * n * n;
  std::vector<std::uint8_t> wall[3] = {std::vector<std::uint8_t>(planes, 0),
                                       std::vector<std::uint8_t>(planes, 0),
                                       std::vector<std::uint8_t>(planes, 0)};
  auto wall_index = [n](int plane, int a, int b) {
    return (static_cast<std::size_t>(plane) * n + b) * n + a;
  };
  const double tol = 0.01;  // in voxels
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const auto& t = mesh.triangles[f];
    Eigen::Vector3d q[3];  // lattice coordinates
    for (int k = 0; k < 3; ++k)
      q[k] = (mesh.vertices[t[k]].cast<double>() - cube.min()) / h;
    int axis = -1;
    for (int a = 0; a < 3 && axis < 0; ++a)
      if (std::abs(q[0][a] - q[1][a]) < tol && std::abs(q[0][a] - q[2][a]) < tol) axis = a;
    const double plane_f = axis >= 0 ? q[0][axis] : 0.0;
    const long plane = std::lround(plane_f);
    if (axis < 0 || std::abs(plane_f - plane) > tol || plane < 0 || plane > n)
      throw std::invalid_argument("voxelize_lattice_surface: triangle " + std::to_string(f) +
                                  " is not an axis-aligned face on the voxel lattice");
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    Eigen::Vector2d p[3];
    for (int k = 0; k < 3; ++k) p[k] = Eigen::Vector2d(q[k][u], q[k][v]);
    const double area = (p[1].x() - p[0].x()) * (p[2].y() - p[0].y()) -
                        (p[1].y() - p[0].y()) * (p[2].x() - p[0].x());
    if (std::abs(area) < tol * tol) continue;
    const double sign = area > 0 ? 1.0 : -1.0;
    const int a0 = std::max(0, static_cast<int>(std::floor(std::min({p[0].x(), p[1].x(), p[2].x()}))));
    const int a1 = std::min(n - 1, static_cast<int>(std::ceil(std::max({p[0].x(), p[1].x(), p[2].x()}))) - 1);
    const int b0 = std::max(0, static_cast<int>(std::floor(std::min({p[0].y(), p[1].y(), p[2].y()}))));
    const int b1 = std::min(n - 1, static_cast<int>(std::ceil(std::max({p[0].y(), p[1].y(), p[2].y()}))) - 1);
    for (int b = b0; b <= b1; ++b)
      for (int a = a0; a <= a1; ++a) {
        // A lattice square belongs to the face when its centre is inside the triangle; centres on
        // the diagonal of a face's two triangles count for both (walls are a union).
        const Eigen::Vector2d x(a + 0.5, b + 0.5);
        bool inside = true;
        for (int k = 0; k < 3 && inside; ++k) {
          const Eigen::Vector2d& s0 = p[k];
          const Eigen::Vector2d& s1 = p[(k + 1) % 3];
          const double e = sign * ((s1.x() - s0.x()) * (x.y() - s0.y()) -
                                   (s1.y() - s0.y()) * (x.x() - s0.x()));
          inside = e >= -1e-9;
        }
        if (inside) wall[axis][wall_index(static_cast<int>(plane), a, b)] = 1;
      }
  }

  // Flood the outside, starting from every border voxel whose border face has no wall.
  std::vector<std::uint8_t> outside(grid.occupancy.size(), 0);
  std::vector<int> stack;  // voxel indices
  auto push = [&](int i, int j, int k) {
    const std::size_t id = grid.index(i, j, k);
    if (!outside[id]) {
      outside[id] = 1;
      stack.push_back(static_cast<int>(id));
    }
  };
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (int plane : {0, n})
      for (int b = 0; b < n; ++b)
        for (int a = 0; a < n; ++a) {
          if (wall[axis][wall_index(plane, a, b)]) continue;
          int ijk[3];
          ijk[axis] = plane == 0 ? 0 : n - 1;
          ijk[u] = a;
          ijk[v] = b;
          push(ijk[0], ijk[1], ijk[2]);
        }
  }
  while (!stack.empty()) {
    const int id = stack.back();
    stack.pop_back();
    int ijk[3] = {id % n, (id / n) % n, id / (n * n)};
    for (int axis = 0; axis < 3; ++axis) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      for (int dir : {-1, 1}) {
        int nb[3] = {ijk[0], ijk[1], ijk[2]};
        nb[axis] += dir;
        if (nb[axis] < 0 || nb[axis] >= n) continue;
        const int plane = std::max(ijk[axis], nb[axis]);  // the lattice plane between them
        if (wall[axis][wall_index(plane, ijk[u], ijk[v])]) continue;
        push(nb[0], nb[1], nb[2]);
      }
    }
  }
  for (std::size_t i = 0; i < grid.occupancy.size(); ++i) grid.occupancy[i] = outside[i] ? 0 : 1;
  return grid;
}

void clip_below(VoxelGrid& grid, double z_min) {
  for (int k = 0; k < grid.n; ++k) {
    if (grid.centre(0, 0, k).z() >= z_min) break;  // layers are ordered by z
    std::fill_n(grid.occupancy.begin() + static_cast<std::ptrdiff_t>(grid.index(0, 0, k)),
                static_cast<std::size_t>(grid.n) * grid.n, std::uint8_t{0});
  }
}

VoxelGrid rasterize_octree(const Octree& octree) {
  check_cube(octree.bounds, "rasterize_octree");
  if (octree.max_depth < 0 || octree.max_depth > 10)
    throw std::invalid_argument("rasterize_octree: max_depth must be in 0..10");
  const int n = 1 << octree.max_depth;
  VoxelGrid grid(octree.bounds, n);
  octree.for_each_occupied_leaf([&](const OctreeCell& c) {
    if (c.depth > octree.max_depth) throw std::invalid_argument("rasterize_octree: node deeper than max_depth");
    // The cell's min corner on the voxel lattice, from its path.
    const int span = 1 << (octree.max_depth - c.depth);
    const int start[3] = {c.x * span, c.y * span, c.z * span};
    for (int k = start[2]; k < start[2] + span; ++k)
      for (int j = start[1]; j < start[1] + span; ++j)
        std::fill_n(grid.occupancy.begin() + static_cast<std::ptrdiff_t>(grid.index(start[0], j, k)),
                    span, std::uint8_t{1});
  });
  return grid;
}

double iou(const VoxelGrid& a, const VoxelGrid& b) {
  if (!a.same_layout(b)) throw std::invalid_argument("iou: grids differ in size or bounds");
  std::size_t inter = 0, uni = 0;
  for (std::size_t i = 0; i < a.occupancy.size(); ++i) {
    const bool x = a.occupancy[i] != 0, y = b.occupancy[i] != 0;
    inter += (x && y);
    uni += (x || y);
  }
  return uni == 0 ? 1.0 : static_cast<double>(inter) / static_cast<double>(uni);
}

std::size_t carved_away(const VoxelGrid& truth, const VoxelGrid& model) {
  if (!truth.same_layout(model))
    throw std::invalid_argument("carved_away: grids differ in size or bounds");
  std::size_t missing = 0;
  for (std::size_t i = 0; i < truth.occupancy.size(); ++i)
    missing += (truth.occupancy[i] != 0 && model.occupancy[i] == 0);
  return missing;
}

TriangleMesh grid_to_mesh(const VoxelGrid& grid) {
  TriangleMesh mesh;
  const int n = grid.n;
  const double h = grid.voxel_size();
  // Lattice corners are shared between faces, so the result is welded and closed.
  std::unordered_map<std::size_t, int> corner_index;
  auto corner = [&](int i, int j, int k) {
    const std::size_t key = (static_cast<std::size_t>(k) * (n + 1) + j) * (n + 1) + i;
    auto [it, inserted] = corner_index.emplace(key, static_cast<int>(mesh.vertices.size()));
    if (inserted)
      mesh.vertices.emplace_back((grid.bounds.min() + h * Eigen::Vector3d(i, j, k)).cast<float>());
    return it->second;
  };
  auto occupied = [&](int i, int j, int k) {
    return i >= 0 && j >= 0 && k >= 0 && i < n && j < n && k < n && grid.occupied(i, j, k);
  };
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        if (!grid.occupied(i, j, k)) continue;
        const int at[3] = {i, j, k};
        for (int axis = 0; axis < 3; ++axis) {
          for (int dir : {-1, 1}) {
            int nb[3] = {i, j, k};
            nb[axis] += dir;
            if (occupied(nb[0], nb[1], nb[2])) continue;
            // The voxel's face towards its empty neighbour: on its far side along axis for +dir.
            add_lattice_square(mesh, axis, dir, at[axis] + (dir > 0 ? 1 : 0), at, 1,
                               [&](const int p[3]) { return corner(p[0], p[1], p[2]); });
          }
        }
      }
  return mesh;
}

}  // namespace fba::geometry
