#include "fba/geometry/object_families.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <stdexcept>

#include <Eigen/Geometry>

namespace fba::geometry {

namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;
using Eigen::Vector3f;

constexpr double kPi = std::numbers::pi;

std::string text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

// Uniform numbers from the top 53 bits of mt19937_64, the same on every standard library
// (std::uniform_real_distribution is not).
class Draws {
 public:
  explicit Draws(std::uint64_t seed) : rng_(seed) {}
  double unit() { return static_cast<double>(rng_() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * unit(); }
  // Uniform in log: every ratio within [lo, hi] as likely as its inverse.
  double log_uniform(double lo, double hi) { return lo * std::exp(std::log(hi / lo) * unit()); }

 private:
  std::mt19937_64 rng_;
};

// A length as the manifest prints it and the mesh is made from it: 0.1 mm.
double mm10(double v) { return std::round(v * 1e4) / 1e4; }
double hundredths(double v) { return std::round(v * 100) / 100; }

// A length a family draws: uniform in [lo, hi], or with `log` log-uniform (every ratio as likely as
// its inverse); recorded as the object's parameter `key`.
struct LengthRange {
  const char* key;
  double lo, hi;
  bool log = false;
};
constexpr bool kLog = true;

Vector3f at(double x, double y, double z) { return Vector3d(x, y, z).cast<float>(); }

int add(TriangleMesh& m, const Vector3f& v) {
  m.vertices.push_back(v);
  return static_cast<int>(m.vertices.size()) - 1;
}

void triangle(TriangleMesh& m, int a, int b, int c) { m.triangles.emplace_back(a, b, c); }

// a, b, c, d counter-clockwise seen from outside.
void quad(TriangleMesh& m, int a, int b, int c, int d) {
  triangle(m, a, b, c);
  triangle(m, a, c, d);
}

// A prism from z0 to z1 on a counter-clockwise loop. Without `inner`, each cap is a fan from
// `kernel`, a point that sees every edge of the loop (inside its kernel, off every edge's line).
// With `inner` (a counter-clockwise loop with as many points, the i-th on the ray from a common
// centre through outer[i]), the prism has a hole: each cap is the strip of quads between the two
// loops, and the inner wall faces the hole's axis.
TriangleMesh prism(const std::vector<Vector2d>& outer, const std::vector<Vector2d>* inner, const Vector2d& kernel, double z0,
                   double z1) {
  TriangleMesh m;
  const int n = static_cast<int>(outer.size());
  for (double z : {z0, z1})
    for (const auto& p : outer) add(m, at(p.x(), p.y(), z));
  const auto ob = [&](int i) { return i % n; };
  const auto ot = [&](int i) { return n + i % n; };
  for (int i = 0; i < n; ++i) quad(m, ob(i), ob(i + 1), ot(i + 1), ot(i));
  if (!inner) {
    const int kb = add(m, at(kernel.x(), kernel.y(), z0)), kt = add(m, at(kernel.x(), kernel.y(), z1));
    for (int i = 0; i < n; ++i) {
      triangle(m, kt, ot(i), ot(i + 1));
      triangle(m, kb, ob(i + 1), ob(i));
    }
    return m;
  }
  for (double z : {z0, z1})
    for (const auto& p : *inner) add(m, at(p.x(), p.y(), z));
  const auto ib = [&](int i) { return 2 * n + i % n; };
  const auto it = [&](int i) { return 3 * n + i % n; };
  for (int i = 0; i < n; ++i) {
    quad(m, ib(i), it(i), it(i + 1), ib(i + 1));     // the hole's wall, facing its axis
    quad(m, it(i), ot(i), ot(i + 1), it(i + 1));     // top cap, +z
    quad(m, ib(i), ib(i + 1), ob(i + 1), ob(i));     // bottom cap, -z
  }
  return m;
}

// Angles about a centre: `count` evenly spread, and the `extra` ones (corners), sorted, one of any
// two closer than a thousandth of a radian dropped (an extra one is kept), in [-pi, pi).
std::vector<double> ray_angles(int count, const std::vector<double>& extra) {
  std::vector<std::pair<double, bool>> all;
  for (int k = 0; k < count; ++k) all.emplace_back(-kPi + 2 * kPi * k / count, false);
  for (double a : extra) all.emplace_back(a >= kPi ? a - 2 * kPi : a, true);
  std::sort(all.begin(), all.end());
  std::vector<std::pair<double, bool>> kept;
  for (const auto& a : all) {
    if (!kept.empty() && a.first - kept.back().first < 1e-3) {
      if (a.second) kept.back() = a;
      continue;
    }
    kept.push_back(a);
  }
  if (kept.size() > 1 && kept.front().first + 2 * kPi - kept.back().first < 1e-3) {
    if (kept.back().second) kept.front() = kept.back();
    kept.pop_back();
  }
  std::vector<double> out;
  for (const auto& a : kept) out.push_back(a.first);
  return out;
}

// Where the ray from `centre` at angle a leaves the rectangle [-hx, hx] x [-hy, hy] (which holds
// the centre inside).
Vector2d rectangle_ray(const Vector2d& centre, double hx, double hy, double a) {
  const Vector2d d(std::cos(a), std::sin(a));
  double t = INFINITY;
  if (d.x() > 1e-12) t = std::min(t, (hx - centre.x()) / d.x());
  if (d.x() < -1e-12) t = std::min(t, (-hx - centre.x()) / d.x());
  if (d.y() > 1e-12) t = std::min(t, (hy - centre.y()) / d.y());
  if (d.y() < -1e-12) t = std::min(t, (-hy - centre.y()) / d.y());
  return centre + t * d;
}

std::vector<double> rectangle_corner_angles(const Vector2d& centre, double hx, double hy) {
  std::vector<double> out;
  for (double sx : {-1.0, 1.0})
    for (double sy : {-1.0, 1.0}) out.push_back(std::atan2(sy * hy - centre.y(), sx * hx - centre.x()));
  return out;
}

ConvexPart box_part(const Vector3d& lo, const Vector3d& hi) {
  ConvexPart p;
  p.kind = ConvexPart::Kind::box;
  p.centre = (lo + hi) / 2;
  p.half = (hi - lo) / 2;
  return p;
}

ConvexPart hull_part(const TriangleMesh& m) {
  ConvexPart p;
  p.points = m.vertices;
  return p;
}

// The object moved so that its bounding box is centred on the origin, its parts with it.
void centre_on_bounds(TriangleMesh& m, std::vector<ConvexPart>& parts) {
  Eigen::AlignedBox3f box;
  for (const auto& v : m.vertices) box.extend(v);
  const Vector3f c = box.center();
  for (auto& v : m.vertices) v -= c;
  for (auto& p : parts) {
    p.centre -= c.cast<double>();
    for (auto& v : p.points) v -= c;
  }
}

double radius(const TriangleMesh& m) {
  double r = 0;
  for (const auto& v : m.vertices) r = std::max(r, v.cast<double>().norm());
  return r;
}

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

const char* const kNames[] = {"box", "cylinder", "sphere", "ellipsoid", "superquadric", "ring", "l_shape", "t_shape", "tool", "holed"};

}  // namespace

const std::vector<ObjectFamily>& all_families() {
  static const std::vector<ObjectFamily> all = {ObjectFamily::box,     ObjectFamily::cylinder, ObjectFamily::sphere, ObjectFamily::ellipsoid,
                                                ObjectFamily::superquadric, ObjectFamily::ring, ObjectFamily::l_shape,
                                                ObjectFamily::t_shape, ObjectFamily::tool,     ObjectFamily::holed};
  return all;
}

std::string_view family_name(ObjectFamily family) { return kNames[static_cast<int>(family)]; }

std::optional<ObjectFamily> family_from_name(std::string_view name) {
  for (ObjectFamily f : all_families())
    if (family_name(f) == name) return f;
  return std::nullopt;
}

std::uint64_t object_seed(std::uint64_t set_seed, ObjectFamily family, int index) {
  std::uint64_t h = 0xcbf29ce484222325ULL;  // FNV-1a
  for (char c : family_name(family)) h = (h ^ static_cast<unsigned char>(c)) * 0x100000001b3ULL;
  return splitmix64(splitmix64(splitmix64(set_seed) ^ h) ^ static_cast<std::uint64_t>(index));
}

TriangleMesh make_box_shape(double sx, double sy, double sz) {
  require(sx > 0 && sy > 0 && sz > 0, "box: expected sizes > 0, found " + text(sx) + " x " + text(sy) + " x " + text(sz));
  const std::vector<Vector2d> loop = {{-sx / 2, -sy / 2}, {sx / 2, -sy / 2}, {sx / 2, sy / 2}, {-sx / 2, sy / 2}};
  // Not geometry::make_box: the same prism as the other families, its caps fanned from the centre.
  return prism(loop, nullptr, Vector2d::Zero(), -sz / 2, sz / 2);
}

TriangleMesh make_cylinder_shape(double radius, double height, int segments) {
  require(radius > 0 && height > 0 && segments >= 3,
          "cylinder: expected radius > 0, height > 0, segments >= 3; found " + text(radius) + ", " + text(height) + ", " + std::to_string(segments));
  std::vector<Vector2d> loop;
  for (int k = 0; k < segments; ++k) loop.emplace_back(radius * std::cos(2 * kPi * k / segments), radius * std::sin(2 * kPi * k / segments));
  return prism(loop, nullptr, Vector2d::Zero(), -height / 2, height / 2);
}

TriangleMesh make_superquadric_shape(const Eigen::Vector3d& semi, double e1, double e2, int n) {
  require(semi.minCoeff() > 0 && e1 > 0 && e1 <= 2 && e2 > 0 && e2 <= 2 && n >= 1,
          "superquadric: expected semi-axes > 0 and exponents in (0, 2]; found " + text(semi.x()) + ", " + text(semi.y()) + ", " +
              text(semi.z()) + " and " + text(e1) + ", " + text(e2));
  // The cube [-1, 1]^3's surface lattice, spaced by equal angles from the centre.
  const auto w = [&](int t) { return std::tan(kPi / 4 * (2.0 * t / n - 1)); };
  const auto surface_point = [&](int i, int j, int k) -> Vector3f {
    const Vector3d d = Vector3d(w(i), w(j), w(k)).normalized();
    const double xy = std::pow(std::abs(d.x() / semi.x()), 2 / e2) + std::pow(std::abs(d.y() / semi.y()), 2 / e2);
    const double f = std::pow(xy, e2 / e1) + std::pow(std::abs(d.z() / semi.z()), 2 / e1);
    return (std::pow(f, -e1 / 2) * d).cast<float>();
  };
  TriangleMesh s;
  std::vector<int> index(static_cast<std::size_t>((n + 1) * (n + 1) * (n + 1)), -1);
  const auto vertex = [&](const Eigen::Vector3i& p) {
    int& id = index[static_cast<std::size_t>((p.x() * (n + 1) + p.y()) * (n + 1) + p.z())];
    if (id < 0) id = add(s, surface_point(p.x(), p.y(), p.z()));
    return id;
  };
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3, c = (a + 2) % 3;  // b x c = a
    for (int side : {0, n})
      for (int u = 0; u < n; ++u)
        for (int v = 0; v < n; ++v) {
          int q[4];
          const int du[4] = {0, 1, 1, 0}, dv[4] = {0, 0, 1, 1};
          for (int k = 0; k < 4; ++k) {
            Eigen::Vector3i p;
            p[a] = side;
            p[b] = u + du[k];
            p[c] = v + dv[k];
            q[k] = vertex(p);
          }
          if (side == n) quad(s, q[0], q[1], q[2], q[3]);
          else quad(s, q[3], q[2], q[1], q[0]);
        }
  }
  return s;
}

TriangleMesh make_ring_shape(double major, double tube_radial, double tube_vertical, int major_segments, int minor_segments) {
  require(tube_radial > 0 && tube_vertical > 0 && major > tube_radial && major_segments >= 3 && minor_segments >= 3,
          "ring: expected tube half-widths > 0 and a major radius above the radial one; found major " + text(major) + ", tube " +
              text(tube_radial) + " x " + text(tube_vertical));
  TriangleMesh s;
  const auto id = [&](int i, int j) { return (i % major_segments) * minor_segments + j % minor_segments; };
  for (int i = 0; i < major_segments; ++i) {
    const double t = 2 * kPi * i / major_segments;
    for (int j = 0; j < minor_segments; ++j) {
      const double p = 2 * kPi * j / minor_segments;
      const double r = major + tube_radial * std::cos(p);
      add(s, at(r * std::cos(t), r * std::sin(t), tube_vertical * std::sin(p)));
    }
  }
  for (int i = 0; i < major_segments; ++i)
    for (int j = 0; j < minor_segments; ++j) quad(s, id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
  return s;
}

TriangleMesh make_l_shape(double length_x, double width_x, double length_y, double width_y, double thickness) {
  require(width_x > 0 && width_y > 0 && thickness > 0 && length_x > width_y && length_y > width_x,
          "L shape: expected widths and thickness > 0, each bar longer than the other is wide; found bars " + text(length_x) + " x " +
              text(width_x) + " and " + text(width_y) + " x " + text(length_y) + ", thickness " + text(thickness));
  const std::vector<Vector2d> loop = {{0, 0}, {length_x, 0}, {length_x, width_x}, {width_y, width_x}, {width_y, length_y}, {0, length_y}};
  return prism(loop, nullptr, Vector2d(width_y / 2, width_x / 2), 0, thickness);
}

TriangleMesh make_t_shape(double bar_length, double bar_width, double stem_length, double stem_width, double thickness) {
  require(bar_width > 0 && stem_length > 0 && stem_width > 0 && thickness > 0 && bar_length > stem_width,
          "T shape: expected sizes > 0 and a bar longer than the stem is wide; found bar " + text(bar_length) + " x " + text(bar_width) +
              ", stem " + text(stem_length) + " x " + text(stem_width) + ", thickness " + text(thickness));
  const double b = bar_length / 2, w = stem_width / 2;
  const std::vector<Vector2d> loop = {{-w, -stem_length}, {w, -stem_length}, {w, 0}, {b, 0}, {b, bar_width}, {-b, bar_width}, {-b, 0}, {-w, 0}};
  return prism(loop, nullptr, Vector2d(0, bar_width / 2), 0, thickness);
}

TriangleMesh make_tool_shape(double handle_radius, double handle_length, double head_x, double head_y, double head_z, int segments) {
  require(handle_radius > 0 && handle_length > 0 && head_x > 0 && 2 * handle_radius < std::min(head_y, head_z) && segments >= 3,
          "tool: expected sizes > 0 and a handle narrower than the head's face; found handle radius " + text(handle_radius) + ", length " +
              text(handle_length) + ", head " + text(head_x) + " x " + text(head_y) + " x " + text(head_z));
  // Built with the handle's axis as the third coordinate w (the head's face across it in u, v),
  // then turned so that w is x: (u, v, w) -> (y, z, x), a rotation.
  const double hu = head_y / 2, hv = head_z / 2;
  const std::vector<double> angles = ray_angles(segments, rectangle_corner_angles(Vector2d::Zero(), hu, hv));
  const int n = static_cast<int>(angles.size());
  TriangleMesh s;
  const auto put = [&](double u, double v, double w) { return add(s, at(w, u, v)); };
  std::vector<Vector2d> face, circle;
  for (double a : angles) {
    face.push_back(rectangle_ray(Vector2d::Zero(), hu, hv, a));
    circle.emplace_back(handle_radius * std::cos(a), handle_radius * std::sin(a));
  }
  std::vector<int> o0, o1, c0, c1;
  for (const auto& p : face) o0.push_back(put(p.x(), p.y(), 0));
  for (const auto& p : face) o1.push_back(put(p.x(), p.y(), head_x));
  for (const auto& p : circle) c0.push_back(put(p.x(), p.y(), 0));
  for (const auto& p : circle) c1.push_back(put(p.x(), p.y(), -handle_length));
  const int top = put(0, 0, head_x), end = put(0, 0, -handle_length);
  for (int i = 0; i < n; ++i) {
    const int j = (i + 1) % n;
    quad(s, o0[i], o0[j], o1[j], o1[i]);  // the head's sides
    triangle(s, top, o1[i], o1[j]);       // the head's far face (+w)
    quad(s, c0[i], c0[j], o0[j], o0[i]);  // the head's near face (-w) around the handle
    quad(s, c1[i], c1[j], c0[j], c0[i]);  // the handle's side
    triangle(s, end, c1[j], c1[i]);       // the handle's end (-w)
  }
  return s;
}

TriangleMesh make_holed_box_shape(double sx, double sy, double sz, bool round, double hole_size, double hole_x, double hole_y, int segments) {
  const double hx = sx / 2, hy = sy / 2;
  // A round hole reaches its radius along x and y from its centre, a square one its half-side.
  require(sz > 0 && hole_size > 0 && std::abs(hole_x) + hole_size < hx && std::abs(hole_y) + hole_size < hy && segments >= 3,
          "holed box: expected a hole inside the box's face; found a box " + text(sx) + " x " + text(sy) + " x " + text(sz) + ", a " +
              (round ? "round hole of radius " : "square hole of half-side ") + text(hole_size) + " at (" + text(hole_x) + ", " +
              text(hole_y) + ")");
  const Vector2d c(hole_x, hole_y);
  std::vector<double> corners = rectangle_corner_angles(c, hx, hy);
  if (!round)
    for (double a : {-3 * kPi / 4, -kPi / 4, kPi / 4, 3 * kPi / 4}) corners.push_back(a);
  const std::vector<double> angles = ray_angles(segments, corners);
  std::vector<Vector2d> outer, inner;
  for (double a : angles) {
    outer.push_back(rectangle_ray(c, hx, hy, a));
    const Vector2d d(std::cos(a), std::sin(a));
    inner.push_back(c + (round ? hole_size : hole_size / std::max(std::abs(d.x()), std::abs(d.y()))) * d);
  }
  return prism(outer, &inner, Vector2d::Zero(), -sz / 2, sz / 2);
}

SolidProperties solid_properties(const TriangleMesh& mesh) {
  SolidProperties out;
  // About the bounding box's centre, for precision; moved back at the end.
  Eigen::AlignedBox3d box;
  for (const auto& v : mesh.vertices) box.extend(v.cast<double>());
  const Vector3d o = mesh.vertices.empty() ? Vector3d(Vector3d::Zero()) : Vector3d(box.center());
  double volume = 0;
  Vector3d first = Vector3d::Zero();
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();  // integral of p p^T
  for (const auto& t : mesh.triangles) {
    const Vector3d a = mesh.vertices[static_cast<std::size_t>(t[0])].cast<double>() - o;
    const Vector3d b = mesh.vertices[static_cast<std::size_t>(t[1])].cast<double>() - o;
    const Vector3d c = mesh.vertices[static_cast<std::size_t>(t[2])].cast<double>() - o;
    const double v = a.dot(b.cross(c)) / 6;  // the signed tetrahedron (o, a, b, c)
    const Vector3d s = a + b + c;
    volume += v;
    first += v * s / 4;
    second += v / 20 * (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose());
  }
  out.volume = volume;
  if (!(volume > 0)) return out;
  const Vector3d centroid = first / volume;
  const Eigen::Matrix3d central = second - volume * centroid * centroid.transpose();
  out.centroid = centroid + o;
  out.inertia = (central.trace() * Eigen::Matrix3d::Identity() - central) / volume;
  return out;
}

FamilyObject make_family_object(ObjectFamily family, std::uint64_t set_seed, int index) {
  // One function: one short case per family, all drawing through the same lambdas and retry loop.
  if (index < 0) throw std::invalid_argument("object families: expected an index >= 0, found " + std::to_string(index));
  FamilyObject o;
  o.family = family;
  o.index = index;
  o.seed = object_seed(set_seed, family, index);
  char name[64];
  std::snprintf(name, sizeof name, "%s-%02d", std::string(family_name(family)).c_str(), index);
  o.name = name;
  Draws d(o.seed);
  const bool even = index % 2 == 0;
  // Drawn until the object stays within kMaxObjectRadius of its centre (a few draws at most: every
  // range below reaches past it only at its corner).
  for (int attempt = 0; attempt < 10000; ++attempt) {
    std::vector<std::pair<std::string, double>> p;
    const auto draw = [&](const char* key, double v) {
      p.emplace_back(key, v);
      return v;
    };
    // A length drawn in its range, to 0.1 mm, and recorded; several in turn, in the order given.
    const auto length = [&](const LengthRange& r) {
      return draw(r.key, mm10(r.log ? d.log_uniform(r.lo, r.hi) : d.uniform(r.lo, r.hi)));
    };
    const auto lengths = [&]<std::size_t N>(const LengthRange(&ranges)[N]) {
      std::array<double, N> out;
      for (std::size_t i = 0; i < N; ++i) out[i] = length(ranges[i]);
      return out;
    };
    TriangleMesh s;
    std::vector<ConvexPart> parts;
    switch (family) {
      case ObjectFamily::box: {
        // Blocks: each side 3-15 cm, log-uniform (every aspect ratio, cubes to sticks); plates:
        // 4-15 cm by 4-15 cm, 1-3 cm thick.
        o.kind = even ? "block" : "plate";
        const auto [sx, sy, sz] = even ? lengths({{"size_x", 0.03, 0.15, kLog}, {"size_y", 0.03, 0.15, kLog}, {"size_z", 0.03, 0.15, kLog}})
                                       : lengths({{"size_x", 0.04, 0.15}, {"size_y", 0.04, 0.15}, {"size_z", 0.01, 0.03}});
        s = make_box_shape(sx, sy, sz);
        parts = {box_part(Vector3d(-sx, -sy, -sz) / 2, Vector3d(sx, sy, sz) / 2)};
        break;
      }
      case ObjectFamily::cylinder: {
        // Radius 1-6 cm; height over diameter 1-4 (long) or 0.2-1 (short, discs), log-uniform;
        // at least 1.5 cm tall.
        o.kind = even ? "long" : "short";
        const double r = length({"radius", 0.01, 0.06});
        const double aspect = even ? d.log_uniform(1, 4) : d.log_uniform(0.2, 1);
        const double h = draw("height", mm10(2 * r * aspect));
        if (h < 0.015) continue;
        s = make_cylinder_shape(r, h);
        parts.emplace_back();
        parts[0].kind = ConvexPart::Kind::cylinder;
        parts[0].half = Vector3d(r, r, h / 2);
        break;
      }
      case ObjectFamily::sphere: {
        o.kind = "sphere";
        const double r = length({"radius", 0.02, 0.07});
        s = make_superquadric_shape(Vector3d::Constant(r), 1, 1);
        parts.emplace_back();
        parts[0].kind = ConvexPart::Kind::ellipsoid;
        parts[0].half = Vector3d::Constant(r);
        break;
      }
      case ObjectFamily::ellipsoid: {
        // Semi-axes 1.5-7.5 cm each, log-uniform.
        o.kind = "ellipsoid";
        const auto [a, b, c] = lengths({{"semi_x", 0.015, 0.075, kLog}, {"semi_y", 0.015, 0.075, kLog}, {"semi_z", 0.015, 0.075, kLog}});
        s = make_superquadric_shape(Vector3d(a, b, c), 1, 1);
        parts.emplace_back();
        parts[0].kind = ConvexPart::Kind::ellipsoid;
        parts[0].half = Vector3d(a, b, c);
        break;
      }
      case ObjectFamily::superquadric: {
        // Semi-axes 2-6.5 cm; exponents 0.2 (a rounded box) to 2 (an octahedron), the convex ones.
        o.kind = "superquadric";
        const auto [a, b, c] = lengths({{"semi_x", 0.02, 0.065}, {"semi_y", 0.02, 0.065}, {"semi_z", 0.02, 0.065}});
        const double e1 = draw("exponent_ns", hundredths(d.uniform(0.2, 2.0)));
        const double e2 = draw("exponent_ew", hundredths(d.uniform(0.2, 2.0)));
        s = make_superquadric_shape(Vector3d(a, b, c), e1, e2);
        parts = {hull_part(s)};
        break;
      }
      case ObjectFamily::ring: {
        // A hole of radius 1-4.5 cm; a tube 2-4 cm across (rim for a pinch), 0.5-2 times that
        // along the ring's axis (a flat washer to a band), log-uniform.
        o.kind = "ring";
        const double hole = d.uniform(0.01, 0.045);
        const double radial = length({"tube_radial", 0.01, 0.02});
        const double vertical = draw("tube_vertical", mm10(radial * d.log_uniform(0.5, 2)));
        const double major = mm10(hole + radial);
        p.insert(p.begin(), {"major_radius", major});
        s = make_ring_shape(major, radial, vertical);
        parts = {hull_part(s)};
        break;
      }
      case ObjectFamily::l_shape: {
        // Bars 6-15 cm and 4-12 cm long, 1.5-4.5 cm wide; 1.5-5 cm thick; each bar at least 1.5 cm
        // longer than the other is wide.
        o.kind = "L";
        const auto [lx, wx, ly, wy, t] = lengths({{"length_x", 0.06, 0.15}, {"width_x", 0.015, 0.045}, {"length_y", 0.04, 0.12},
                                                  {"width_y", 0.015, 0.045}, {"thickness", 0.015, 0.05}});
        if (lx < wy + 0.015 || ly < wx + 0.015) continue;
        s = make_l_shape(lx, wx, ly, wy, t);
        parts = {box_part(Vector3d(0, 0, 0), Vector3d(lx, wx, t)), box_part(Vector3d(0, 0, 0), Vector3d(wy, ly, t))};
        break;
      }
      case ObjectFamily::t_shape: {
        // A bar 6-15 cm long, 1.5-4.5 cm wide; a stem 3-10 cm beyond it, 1.5-4.5 cm wide; 1.5-5 cm
        // thick; the bar at least 3 cm longer than the stem is wide.
        o.kind = "T";
        const auto [bl, bw, sl, sw, t] = lengths({{"bar_length", 0.06, 0.15}, {"bar_width", 0.015, 0.045}, {"stem_length", 0.03, 0.10},
                                                  {"stem_width", 0.015, 0.045}, {"thickness", 0.015, 0.05}});
        if (bl < sw + 0.03) continue;
        s = make_t_shape(bl, bw, sl, sw, t);
        parts = {box_part(Vector3d(-bl / 2, 0, 0), Vector3d(bl / 2, bw, t)), box_part(Vector3d(-sw / 2, -sl, 0), Vector3d(sw / 2, 0, t))};
        break;
      }
      case ObjectFamily::tool: {
        // A handle of radius 0.8-1.8 cm, 5-12 cm long; a head 1.5-6 cm along the handle, 3-12 cm
        // across, 2-5 cm tall, whose face leaves at least 3 mm around the handle.
        o.kind = "tool";
        const auto [rh, lh, hx, hy, hz] = lengths({{"handle_radius", 0.008, 0.018}, {"handle_length", 0.05, 0.12}, {"head_x", 0.015, 0.06},
                                                   {"head_y", 0.03, 0.12}, {"head_z", 0.02, 0.05}});
        if (std::min(hy, hz) < 2 * rh + 0.006) continue;
        s = make_tool_shape(rh, lh, hx, hy, hz);
        parts = {box_part(Vector3d(0, -hy / 2, -hz / 2), Vector3d(hx, hy / 2, hz / 2))};
        ConvexPart handle;  // along x: its own z is the object's x (its x, y the object's y, z)
        handle.kind = ConvexPart::Kind::cylinder;
        handle.centre = Vector3d(-lh / 2, 0, 0);
        handle.axes << 0, 0, 1, 1, 0, 0, 0, 1, 0;
        handle.half = Vector3d(rh, rh, lh / 2);
        parts.push_back(handle);
        break;
      }
      case ObjectFamily::holed: {
        // A box 5-15 cm by 5-15 cm, 1.5-6 cm thick, with a hole through its thickness, round or
        // square (alternately), of radius or half-side 0.6 cm up to what leaves walls of 1.2 cm,
        // placed anywhere that leaves walls of 1 cm.
        o.kind = even ? "round hole" : "square hole";
        const auto [sx, sy, sz] = lengths({{"size_x", 0.05, 0.15}, {"size_y", 0.05, 0.15}, {"size_z", 0.015, 0.06}});
        const double size = length({even ? "hole_radius" : "hole_half_side", 0.006, std::min(sx, sy) / 2 - 0.012});
        const double mx = sx / 2 - size - 0.01, my = sy / 2 - size - 0.01;
        const auto [x, y] = lengths({{"hole_x", -mx, mx}, {"hole_y", -my, my}});
        s = make_holed_box_shape(sx, sy, sz, even, size, x, y);
        parts = {box_part(Vector3d(-sx, -sy, -sz) / 2, Vector3d(sx, sy, sz) / 2)};  // its hull
        break;
      }
    }
    centre_on_bounds(s, parts);
    if (radius(s) > kMaxObjectRadius) continue;
    o.parameters = std::move(p);
    o.mesh = std::move(s);
    o.parts = std::move(parts);
    return o;
  }
  throw std::logic_error("object families: no " + o.name + " within " + text(kMaxObjectRadius) + " m of its centre in 10000 draws");
}

}  // namespace fba::geometry
