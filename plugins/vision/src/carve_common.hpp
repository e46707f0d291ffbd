// The fast carver's node test (see octree_carver.hpp): corner positions on an integer lattice, the
// rectangle rule, occupancy, the leaf test. reference_carve.cpp writes the same rules again on its
// own (and projects every corner with P * X where node_rect() below adds projected edges), so it
// is an independent oracle; the two agree except when a projection lands within rounding error
// (~1e-13 px) of a pixel edge, which the benchmark and the tests check by counting mismatches. A
// pixel is the closed unit square around its centre; the tolerance tol
// (CarverParams::silhouette_tolerance, pixels) is how far from a projection a silhouette pixel's
// square may lie and still count.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "fba/types/regions_of_interest.hpp"
#include "fba/types/silhouette.hpp"
#include "fba/vision/octree_carver.hpp"

namespace fba::vision::detail {

// One silhouette prepared for O(1) rectangle sums.
struct ViewData {
  Eigen::Matrix<double, 3, 4> P;
  int width = 0, height = 0;
  cv::Mat mask;                // CV_8U, non-zero inside (for the leaf centre test)
  cv::Mat integral;            // CV_32S, (h+1) x (w+1), of the mask as 0/1
  cv::Mat graspable_integral;  // CV_32S, of contour points with curvature < threshold; empty = off
  // Pixels outside the image are empty (the silhouette lies inside it: carve_outside_view), not
  // unknown.
  bool outside_empty = false;
};

ViewData make_view(const fba::Silhouette& s, const CarverParams& p);

// Corners live on a lattice of 2^20 cells per edge, whatever the tree depth, so a corner has the
// same coordinates (bit for bit) in trees of any depth: ix / 2^20 is exact in binary.
inline constexpr int kLatticeBits = 20;
inline constexpr double kInvCells = 1.0 / double(1 << kLatticeBits);

struct Lattice {
  Eigen::Vector3d origin;  // the root cube's min corner
  double edge = 0;         // the root cube's edge
  Eigen::Vector3d corner(int ix, int iy, int iz) const {
    return origin + edge * Eigen::Vector3d(ix * kInvCells, iy * kInvCells, iz * kInvCells);
  }
};
inline int cells_at_depth(int depth) { return 1 << (kLatticeBits - depth); }  // node edge in cells

// A node: its min corner in lattice cells and its depth.
struct NodeKey {
  int ix = 0, iy = 0, iz = 0, depth = 0;
  NodeKey child(int c) const {
    const int h = cells_at_depth(depth + 1);
    return {ix + (c & 1) * h, iy + ((c >> 1) & 1) * h, iz + ((c >> 2) & 1) * h, depth + 1};
  }
};

// The node's rectangle in one view: pixel bounds (inclusive), or behind = a corner is not in
// front of the camera. It holds every pixel whose square comes within tol of the projected
// corners' bounding box (per axis), so every pixel whose square is within tol of some point of
// the node's projection.
struct Rect {
  int x0 = 0, y0 = 0, x1 = -1, y1 = -1;
  bool behind = false;
};

// Pixel centres sit at integer coordinates: the pixels whose centre lies in [lo, hi], as
// [first, last] (empty when first > last). The clamp keeps far-off projections (corners near
// the camera plane) inside int range.
inline int first_pixel(double lo) { return static_cast<int>(std::ceil(std::clamp(lo, -1e8, 1e8))); }
inline int last_pixel(double hi) { return static_cast<int>(std::floor(std::clamp(hi, -1e8, 1e8))); }

// The rectangle of a projected bounding box [umin, umax] x [vmin, vmax] with tolerance tol: the
// pixels whose centre is within tol + 1/2 of it. Never empty (an interval of length >= 1 holds an
// integer).
inline Rect pixel_rect(double umin, double umax, double vmin, double vmax, double tol) {
  const double g = tol + 0.5;
  Rect r;
  r.x0 = first_pixel(umin - g), r.x1 = last_pixel(umax + g);
  r.y0 = first_pixel(vmin - g), r.y1 = last_pixel(vmax + g);
  return r;
}

// The 8 corners in homogeneous image coordinates, from the min corner's projection plus the
// projected edge vectors (7 additions instead of 8 matrix products).
struct Corners {
  double x[8], y[8], z[8];
};

inline Corners project_corners(const ViewData& v, const Lattice& L, const NodeKey& k) {
  const Eigen::Vector3d X = L.corner(k.ix, k.iy, k.iz);
  const double s = L.edge * (cells_at_depth(k.depth) * kInvCells);  // the node's edge, metres
  const double* P = v.P.data();  // column-major 3x4
  const double h0[3] = {P[0] * X.x() + P[3] * X.y() + P[6] * X.z() + P[9],
                        P[1] * X.x() + P[4] * X.y() + P[7] * X.z() + P[10],
                        P[2] * X.x() + P[5] * X.y() + P[8] * X.z() + P[11]};
  Corners c;
  for (int r = 0; r < 3; ++r) {
    double* out = r == 0 ? c.x : r == 1 ? c.y : c.z;
    const double ex = P[r] * s, ey = P[3 + r] * s, ez = P[6 + r] * s;
    out[0] = h0[r];
    out[1] = h0[r] + ex;
    out[2] = h0[r] + ey;
    out[3] = out[1] + ey;
    out[4] = h0[r] + ez;
    out[5] = out[1] + ez;
    out[6] = out[2] + ez;
    out[7] = out[3] + ez;
  }
  return c;
}

// The 8 corners in pixels; false when one is not in front of the camera.
inline bool project_corners_uv(const ViewData& v, const Lattice& L, const NodeKey& k, double u[8], double w[8]) {
  const Corners c = project_corners(v, L, k);
  for (int i = 0; i < 8; ++i) {
    if (!(c.z[i] > 0)) return false;
    const double inv = 1.0 / c.z[i];
    u[i] = c.x[i] * inv, w[i] = c.y[i] * inv;
  }
  return true;
}

inline Rect rect_of(const double u[8], const double w[8], double tol) {
  double umin = INFINITY, umax = -INFINITY, vmin = INFINITY, vmax = -INFINITY;
  for (int i = 0; i < 8; ++i) {
    umin = std::min(umin, u[i]), umax = std::max(umax, u[i]);
    vmin = std::min(vmin, w[i]), vmax = std::max(vmax, w[i]);
  }
  return pixel_rect(umin, umax, vmin, vmax, tol);
}

inline Rect node_rect(const ViewData& v, const Lattice& L, const NodeKey& k, double tol) {
  double u[8], w[8];
  if (!project_corners_uv(v, L, k, u, w)) {
    Rect r;
    r.behind = true;
    return r;
  }
  return rect_of(u, w, tol);
}

inline std::int64_t rect_sum(const cv::Mat& I, int x0, int y0, int x1, int y1) {
  // I is (h+1) x (w+1): sum over [x0, x1] x [y0, y1] inclusive.
  const int* top = I.ptr<int>(y0);
  const int* bot = I.ptr<int>(y1 + 1);
  return std::int64_t(bot[x1 + 1]) - top[x1 + 1] - bot[x0] + top[x0];
}

// Occupied pixels (silhouette + outside the image) and the rectangle's area.
struct Occupancy {
  std::int64_t occupied = 0, area = 1;
  bool empty() const { return occupied == 0; }
  bool full() const { return occupied == area; }
  double value() const { return double(occupied) / double(area); }
};

inline Occupancy occupancy(const ViewData& v, const Rect& r) {
  if (r.behind) return {1, 1};  // unknown: never carve, never call it inside
  const std::int64_t area = std::int64_t(r.x1 - r.x0 + 1) * std::int64_t(r.y1 - r.y0 + 1);
  const int cx0 = std::max(r.x0, 0), cx1 = std::min(r.x1, v.width - 1);
  const int cy0 = std::max(r.y0, 0), cy1 = std::min(r.y1, v.height - 1);
  const std::int64_t outside = v.outside_empty ? 0 : 1;  // what a pixel outside the image counts
  if (cx0 > cx1 || cy0 > cy1) return {area * outside, area};  // wholly outside the image
  const std::int64_t in_image = std::int64_t(cx1 - cx0 + 1) * (cy1 - cy0 + 1);
  return {rect_sum(v.integral, cx0, cy0, cx1, cy1) + (area - in_image) * outside, area};
}

// The generic criterion's share: the node's projection is the convex hull of its 8 projected
// corners (a hexagon in general position), so unlike the rectangle's share it does not depend on
// how the cube is turned in the image. Share = occupied pixels (silhouette, or outside the image)
// among the pixels whose centre lies in the hull, counted row by row with the integral image.
// A hull holding no pixel centre (a node under about a pixel) takes the rectangle's share. The
// node's state is the rectangle's (O(1)); for a Partial node (rectangle neither empty nor full)
// the share is clamped into the open interval (0, 1), so occupancy_threshold 0 splits every
// Partial node as the rectangle rule did.
inline double hull_share(const ViewData& v, const double u[8], const double w[8], const Occupancy& rect) {
  // Andrew's monotone chain on 8 points: the hull counter-clockwise in (u, w).
  int idx[8] = {0, 1, 2, 3, 4, 5, 6, 7};
  std::sort(idx, idx + 8, [&](int a, int b) { return u[a] < u[b] || (u[a] == u[b] && w[a] < w[b]); });
  double hu[16], hw[16];
  int n = 0;
  auto cross = [&](int i, int j, int p) {
    return (hu[j] - hu[i]) * (w[p] - hw[i]) - (hw[j] - hw[i]) * (u[p] - hu[i]);
  };
  for (int i = 0; i < 8; ++i) {
    while (n >= 2 && cross(n - 2, n - 1, idx[i]) <= 0) --n;
    hu[n] = u[idx[i]], hw[n] = w[idx[i]], ++n;
  }
  for (int i = 6, lower = n + 1; i >= 0; --i) {
    while (n >= lower && cross(n - 2, n - 1, idx[i]) <= 0) --n;
    hu[n] = u[idx[i]], hw[n] = w[idx[i]], ++n;
  }
  --n;  // the last point repeats the first
  double wmin = INFINITY, wmax = -INFINITY;
  for (int i = 0; i < n; ++i) wmin = std::min(wmin, hw[i]), wmax = std::max(wmax, hw[i]);
  std::int64_t area = 0, occupied = 0;
  for (int y = first_pixel(wmin), y1 = last_pixel(wmax); y <= y1; ++y) {
    // The hull's span on the row of pixel centres at height y: its edges crossing that height.
    double lo = INFINITY, hi = -INFINITY;
    for (int i = 0; i < n; ++i) {
      const int j = i + 1 == n ? 0 : i + 1;
      const double a = hw[i], b = hw[j];
      if ((y < a && y < b) || (y > a && y > b)) continue;
      const double x = a == b ? hu[i] : hu[i] + (hu[j] - hu[i]) * ((y - a) / (b - a));
      lo = std::min({lo, x, a == b ? hu[j] : x}), hi = std::max({hi, x, a == b ? hu[j] : x});
    }
    const int x0 = first_pixel(lo), x1 = last_pixel(hi);
    if (x0 > x1) continue;
    const std::int64_t row = x1 - x0 + 1;
    area += row;
    const std::int64_t outside = v.outside_empty ? 0 : 1;  // unknown (occupied) unless empty
    if (y < 0 || y >= v.height) {
      occupied += row * outside;
      continue;
    }
    const int cx0 = std::max(x0, 0), cx1 = std::min(x1, v.width - 1);
    const std::int64_t in_image = cx0 <= cx1 ? cx1 - cx0 + 1 : 0;
    occupied += (row - in_image) * outside + (in_image > 0 ? rect_sum(v.integral, cx0, y, cx1, y) : 0);
  }
  const double share = area > 0 ? double(occupied) / double(area) : rect.value();
  return std::clamp(share, 1e-9, 1 - 1e-9);
}

// Whether a graspable contour point lies in the (clipped) rectangle.
inline bool graspable_contour_in(const ViewData& v, const Rect& r) {
  if (v.graspable_integral.empty() || r.behind) return false;
  const int cx0 = std::max(r.x0, 0), cx1 = std::min(r.x1, v.width - 1);
  const int cy0 = std::max(r.y0, 0), cy1 = std::min(r.y1, v.height - 1);
  if (cx0 > cx1 || cy0 > cy1) return false;
  return rect_sum(v.graspable_integral, cx0, cy0, cx1, cy1) > 0;
}

inline bool intersects_roi(const fba::RegionsOfInterest& roi, const Lattice& L, const NodeKey& k) {
  if (roi.boxes.empty()) return false;
  const int s = cells_at_depth(k.depth);
  const Eigen::AlignedBox3d box(L.corner(k.ix, k.iy, k.iz), L.corner(k.ix + s, k.iy + s, k.iz + s));
  for (const auto& b : roi.boxes)
    if (!b.isEmpty() && b.intersects(box)) return true;
  return false;
}

// The leaf test (see octree_carver.hpp). A view may carve a leaf only if it knows every pixel
// within the tolerance of the projection: the node in front of the camera and its rectangle
// inside the image, or anywhere in front when the pixels outside the image are known empty.
inline bool rect_inside_image(const ViewData& v, const Rect& r) {
  return !r.behind && (v.outside_empty || (r.x0 >= 0 && r.y0 >= 0 && r.x1 < v.width && r.y1 < v.height));
}

// Whether view v carves a leaf whose rectangle is r and whose centre projects to (u, w): no
// silhouette pixel's square lies within tol of (u, w). The candidate pixels (centres within
// tol + 1/2 per axis) are inside r, since the centre projects inside the corners' bounding box
// (those outside the image, when it may carve there, are empty); their integral-image sum settles the common cases, and only a window
// holding both kinds of pixel is checked pixel by pixel (at most 9 pixels for tol = sqrt(2)/2).
inline bool leaf_carved_by(const ViewData& v, const Rect& r, double u, double w, double tol) {
  if (!rect_inside_image(v, r)) return false;
  const double g = tol + 0.5;
  const int x0 = std::max(first_pixel(u - g), 0), x1 = std::min(last_pixel(u + g), v.width - 1);
  const int y0 = std::max(first_pixel(w - g), 0), y1 = std::min(last_pixel(w + g), v.height - 1);
  if (x0 > x1 || y0 > y1) return v.outside_empty;  // the window is wholly outside the image
  const std::int64_t in = rect_sum(v.integral, x0, y0, x1, y1);
  if (in == 0) return true;
  if (in == std::int64_t(x1 - x0 + 1) * (y1 - y0 + 1)) return false;  // the pixel under (u, w) is in
  for (int y = y0; y <= y1; ++y) {
    const std::uint8_t* row = v.mask.ptr<std::uint8_t>(y);
    const double dy = std::max(std::abs(y - w) - 0.5, 0.0);  // from (u, w) to the square's rows
    for (int x = x0; x <= x1; ++x) {
      const double dx = std::max(std::abs(x - u) - 0.5, 0.0);
      if (row[x] != 0 && dx * dx + dy * dy <= tol * tol) return false;
    }
  }
  return true;
}

// The node's centre, projected; false when behind the camera.
inline bool project_centre(const ViewData& v, const Lattice& L, const NodeKey& k, double& u, double& w) {
  const int h = cells_at_depth(k.depth) / 2;
  const Eigen::Vector3d X = L.corner(k.ix + h, k.iy + h, k.iz + h);
  const double* P = v.P.data();  // column-major 3x4
  const double z = P[2] * X.x() + P[5] * X.y() + P[8] * X.z() + P[11];
  if (!(z > 0)) return false;
  const double inv = 1.0 / z;
  u = (P[0] * X.x() + P[3] * X.y() + P[6] * X.z() + P[9]) * inv;
  w = (P[1] * X.x() + P[4] * X.y() + P[7] * X.z() + P[10]) * inv;
  return true;
}

inline bool at_resolution_limit(const CarverParams& p, const Lattice& L, int depth) {
  return depth >= p.max_depth || L.edge * cells_at_depth(depth) * kInvCells <= p.min_node_size;
}

// The leaf test applies to the leaves at the resolution limit that are not wholly inside every
// view (a wholly inside node has silhouette pixels all round its centre).
enum class Split { No, Generic, Grasp };

inline bool wants_leaf_test(const CarverParams& p, const Lattice& L, int depth, double min_occ) {
  return min_occ < 1 && at_resolution_limit(p, L, depth);
}

inline void check_params(const CarverParams& p) {
  if (p.max_depth < 0 || p.max_depth >= kLatticeBits)
    throw std::invalid_argument("CarverParams.max_depth: expected 0..19, found " + std::to_string(p.max_depth));
  if (p.min_node_size < 0 || p.occupancy_threshold < 0 || p.occupancy_threshold > 1)
    throw std::invalid_argument("CarverParams: expected min_node_size >= 0 and occupancy_threshold in 0..1");
  if (p.generic_depth < 0 || p.generic_depth >= kLatticeBits)
    throw std::invalid_argument("CarverParams.generic_depth: expected 0..19, found " + std::to_string(p.generic_depth));
  if (p.detail_after_views < 0 || p.detail_depth < 0)
    throw std::invalid_argument("CarverParams: expected detail_after_views >= 0 and detail_depth >= 0");
  if (!(p.silhouette_tolerance >= 0 && p.silhouette_tolerance <= 64))
    throw std::invalid_argument("CarverParams.silhouette_tolerance: expected 0..64 pixels, found " +
                                std::to_string(p.silhouette_tolerance));
}

}  // namespace fba::vision::detail
