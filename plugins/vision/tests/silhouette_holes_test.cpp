// Objects you can see through, rendered by the simulated camera's renderer: the extraction keeps
// their through-holes in the silhouette, and the carver carves them out.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <memory>
#include <numbers>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "fba/geometry/mesh_io.hpp"
#include "fba/geometry/renderer.hpp"
#include "fba/geometry/viewpoints.hpp"
#include "fba/geometry/voxelize.hpp"
#include "fba/vision/contour_extraction.hpp"
#include "fba/vision/octree_carver.hpp"
#include "fba/vision/reference_carve.hpp"

using namespace fba;

namespace {

constexpr int kDepth = 6;

// A torus around the z axis: radius R to the tube's centre, tube radius r.
TriangleMesh torus(double R, double r, int nu = 96, int nv = 48) {
  TriangleMesh m;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * std::numbers::pi * i / nu, v = 2 * std::numbers::pi * j / nv;
      m.vertices.emplace_back((R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v));
    }
  auto id = [&](int i, int j) { return (i % nu) * nv + j % nv; };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      m.triangles.emplace_back(id(i, j), id(i + 1, j), id(i + 1, j + 1));
      m.triangles.emplace_back(id(i, j), id(i + 1, j + 1), id(i, j + 1));
    }
  return m;
}

// A mug: a solid cylinder (the body) and a ring handle in the xz plane beside it, as voxels
// turned into a closed surface, so body and handle join without overlapping faces.
TriangleMesh mug() {
  geometry::VoxelGrid g(Eigen::AlignedBox3d(Eigen::Vector3d::Constant(-0.08), Eigen::Vector3d::Constant(0.08)), 64);
  for (int k = 0; k < g.n; ++k)
    for (int j = 0; j < g.n; ++j)
      for (int i = 0; i < g.n; ++i) {
        const Eigen::Vector3d p = g.centre(i, j, k);
        const bool body = std::hypot(p.x() + 0.02, p.y()) < 0.035 && std::abs(p.z()) < 0.045;
        const double ring = std::hypot(p.x() - 0.035, p.z());
        const bool handle = ring > 0.015 && ring < 0.025 && std::abs(p.y()) < 0.008;
        if (body || handle) g.set(i, j, k);
      }
  return geometry::grid_to_mesh(g);
}

// Scissors lying flat (8 mm thick, centred on z = 0): two tapered blades crossing at the pivot,
// handles back to two finger loops (inner radius 12 mm, outer 19 mm) centred at (-0.055,
// +-0.025), as voxels turned into a closed surface.
constexpr double kLoopX = -0.055, kLoopY = 0.025, kLoopInner = 0.012, kLoopOuter = 0.019, kHalfThickness = 0.004;

TriangleMesh scissors() {
  // Distance from p to the segment [a, b] in the xy plane.
  auto to_segment = [](const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    const Eigen::Vector2d d = b - a;
    const double t = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
    return std::make_pair((p - a - t * d).norm(), t);
  };
  geometry::VoxelGrid g(Eigen::AlignedBox3d(Eigen::Vector3d::Constant(-0.1), Eigen::Vector3d::Constant(0.1)), 96);
  for (int k = 0; k < g.n; ++k)
    for (int j = 0; j < g.n; ++j)
      for (int i = 0; i < g.n; ++i) {
        const Eigen::Vector3d c = g.centre(i, j, k);
        if (std::abs(c.z()) >= kHalfThickness) continue;
        const Eigen::Vector2d p = c.head<2>();
        bool in = false;
        for (double side : {-1.0, 1.0}) {
          // A blade from just behind the pivot to its tip, 7 degrees off the x axis, 7 mm wide at
          // the pivot narrowing to 1 mm.
          const double a = side * 7 * std::numbers::pi / 180;
          const Eigen::Vector2d dir(std::cos(a), std::sin(a));
          const auto [blade, t] = to_segment(p, -0.01 * dir, 0.09 * dir);
          in = in || blade < 0.0035 - 0.003 * t;
          // The handle, from the pivot to the loop's rim, and the loop.
          const Eigen::Vector2d loop(kLoopX, side * kLoopY);
          const double r = (p - loop).norm();
          in = in || (r >= kLoopInner && (r <= kLoopOuter || to_segment(p, Eigen::Vector2d::Zero(), loop).first < 0.004));
        }
        if (in) g.set(i, j, k);
      }
  return geometry::grid_to_mesh(g);
}

struct Carved {
  std::vector<Silhouette> silhouettes;
  std::vector<cv::Mat> rendered_masks;
  geometry::VoxelGrid model;
};

// The root cube of the carves: the mesh's box grown by 10%.
Eigen::AlignedBox3d root_cube(const TriangleMesh& mesh) { return geometry::cube_around(geometry::mesh_bounds(mesh), 0.1); }

// Renders the mesh from `views` views over the upper hemisphere on a black background and
// extracts the silhouettes from the colour images (the model is left empty).
Carved render_extract(const TriangleMesh& mesh, const vision::ExtractionParams& p, int views = 12) {
  const Eigen::AlignedBox3d box = geometry::mesh_bounds(mesh);
  const int size = 320;
  const double focal = 400;
  geometry::RenderOptions look;
  look.background_top = look.background_bottom = cv::Vec3b(0, 0, 0);
  Carved out;
  for (const auto& pose : geometry::hemisphere_views(views, 0.15, 1.45, geometry::framing_distance(box, size, size, focal),
                                                     box.center())) {
    const CameraModel cam = geometry::make_camera(size, size, focal, focal, (size - 1) / 2.0, (size - 1) / 2.0, pose);
    const geometry::RenderResult r = geometry::render(mesh, cam, look);
    auto frame = std::make_shared<Frame>();
    frame->image = r.colour;
    frame->camera = cam;
    frame->has_pose = true;
    frame->source = "sim";
    const vision::ExtractionResult e = vision::extract_silhouette(frame, p);
    if (!e.ok()) throw std::runtime_error(e.error);
    out.silhouettes.push_back(*e.silhouette);
    out.rendered_masks.push_back(r.mask);
  }
  return out;
}

// The silhouettes carved with uniform detail, as a grid.
geometry::VoxelGrid carve(const TriangleMesh& mesh, const std::vector<Silhouette>& silhouettes) {
  vision::CarverParams cp;
  cp.max_depth = kDepth;
  cp.detail_after_views = 0;
  vision::OctreeCarver carver(cp);
  carver.set_bounds(root_cube(mesh));
  carver.add_views(silhouettes);
  return geometry::rasterize_octree(*carver.snapshot());
}

// Renders, extracts and carves.
Carved render_extract_carve(const TriangleMesh& mesh, const vision::ExtractionParams& p, int views = 12) {
  Carved out = render_extract(mesh, p, views);
  out.model = carve(mesh, out.silhouettes);
  return out;
}

vision::ExtractionParams params(bool holes) {
  vision::ExtractionParams p;
  // Shaded faces are at least 25% (ambient) of the object's grey of ~165; the background is 0.
  p.binarise.threshold = 0.08;
  p.binarise.dilate_px = p.binarise.erode_px = 0;
  if (!holes) p.selection.min_hole_area_px = std::numeric_limits<double>::infinity();
  return p;
}

struct Counts {
  std::size_t voxels = 0, occupied = 0;
};

Counts count_in(const geometry::VoxelGrid& g, const std::function<bool(const Eigen::Vector3d&)>& region) {
  Counts c;
  for (int k = 0; k < g.n; ++k)
    for (int j = 0; j < g.n; ++j)
      for (int i = 0; i < g.n; ++i)
        if (region(g.centre(i, j, k))) ++c.voxels, c.occupied += g.occupied(i, j, k);
  return c;
}

// The rule checked on each object: (a) the hole is in the masks, which hold every rendered
// object pixel; (b) the carve empties the through-hole that the filled silhouettes leave full;
// (c) it is closer to the true voxelisation, as close as the renderer's exact masks get, and
// still never carves a true voxel.
void check_through_hole(const TriangleMesh& mesh, const std::function<bool(const Eigen::Vector3d&)>& hole) {
  const Carved with = render_extract_carve(mesh, params(true));
  const Carved filled = render_extract_carve(mesh, params(false));

  std::size_t views_with_holes = 0;
  for (std::size_t v = 0; v < with.silhouettes.size(); ++v) {
    const Silhouette& s = with.silhouettes[v];
    EXPECT_EQ(cv::countNonZero(with.rendered_masks[v] & ~s.mask), 0) << "view " << v;
    // Open pixels inside the outline are exactly those of the holes it reports.
    const int open = cv::countNonZero(s.mask != filled.silhouettes[v].mask);
    EXPECT_EQ(open > 0, !s.holes.empty()) << "view " << v;
    views_with_holes += !s.holes.empty();
    EXPECT_TRUE(filled.silhouettes[v].holes.empty());
  }
  EXPECT_GE(views_with_holes, 3u);

  const Counts core_with = count_in(with.model, hole), core_filled = count_in(filled.model, hole);
  ASSERT_GT(core_with.voxels, 20u);
  EXPECT_EQ(core_with.occupied, 0u) << "of " << core_with.voxels << " voxels in the through-hole";
  EXPECT_EQ(core_filled.occupied, core_filled.voxels);

  const geometry::VoxelGrid truth = geometry::voxelize(mesh, with.model.bounds, kDepth);
  const double iou_with = geometry::iou(truth, with.model), iou_filled = geometry::iou(truth, filled.model);
  EXPECT_GT(iou_with, iou_filled + 0.02) << "with holes " << iou_with << ", filled " << iou_filled;
  EXPECT_EQ(geometry::carved_away(truth, with.model), 0u);
  // For scale: the renderer's own masks (exact), carved the same way.
  std::vector<Silhouette> exact = with.silhouettes;
  for (std::size_t v = 0; v < exact.size(); ++v) exact[v].mask = with.rendered_masks[v];
  const double iou_exact = geometry::iou(truth, carve(mesh, exact));
  ::testing::Test::RecordProperty("iou_with_holes", std::to_string(iou_with));
  ::testing::Test::RecordProperty("iou_holes_filled", std::to_string(iou_filled));
  ::testing::Test::RecordProperty("iou_exact_masks", std::to_string(iou_exact));
  std::printf("voxel IoU against the true voxelisation: %.4f with holes, %.4f holes filled, %.4f exact masks\n", iou_with,
              iou_filled, iou_exact);
  EXPECT_GE(iou_with, iou_exact - 0.01);  // the extracted silhouettes lose (almost) nothing against exact masks
}

}  // namespace

TEST(ThroughHoles, TorusHoleIsKeptInTheSilhouettesAndCarved) {
  const double R = 0.05, r = 0.015;
  // The middle of the hole: well inside the tube's inner edge (R - r), within the tube's height.
  check_through_hole(torus(R, r), [&](const Eigen::Vector3d& p) {
    return std::hypot(p.x(), p.y()) < 0.6 * (R - r) && std::abs(p.z()) < 0.8 * r;
  });
}

TEST(ThroughHoles, MugHandleHoleIsKeptInTheSilhouettesAndCarved) {
  check_through_hole(mug(), [](const Eigen::Vector3d& p) {
    return std::hypot(p.x() - 0.035, p.z()) < 0.6 * 0.015 && std::abs(p.y()) < 0.006;
  });
}

// The grasp-specific criterion (Algorithm 2 on the contour) reads the holes' contours as outline
// too: the rim of the mug's handle hole is where fingers hook, and it is concave (the hole's
// outward normal points into the hole), so graspable at a negative curvature_threshold. With the
// generic criterion off, the carve is refined to the finest level all along that rim, as a
// uniform carve is; the same masks with the hole contours left out refine only where the outer
// contour is concave (the handle's joints with the body), not on the rim. The fast carver and the
// reference agree on every leaf.
TEST(ThroughHoles, GraspCriterionRefinesAlongTheRimOfTheHandlesHole) {
  const TriangleMesh m = mug();
  const Carved with = render_extract(m, params(true));
  std::vector<Silhouette> outer_only = with.silhouettes;
  for (auto& s : outer_only) s.holes.clear();  // the masks keep their holes

  vision::CarverParams cp;
  cp.max_depth = kDepth;
  cp.detail_after_views = 0;
  cp.occupancy_threshold = 1;  // the generic criterion off: only the contour's curvature splits
  cp.curvature_threshold = -0.02;  // clearly concave: a radius under 50 px (the hole's is about 28 px)
  const Eigen::AlignedBox3d cube = root_cube(m);
  auto carve = [&](const std::vector<Silhouette>& views) {
    vision::OctreeCarver carver(cp);
    carver.set_bounds(cube);
    carver.add_views(views);
    return carver.snapshot();
  };
  const auto holes = carve(with.silhouettes), outer = carve(outer_only);
  const Octree reference = vision::reference_carve(with.silhouettes, cube, cp);
  EXPECT_EQ(vision::count_leaf_mismatches(*holes, reference), 0u);
  EXPECT_EQ(vision::count_leaf_mismatches(reference, *holes), 0u);

  // The rim: the handle ring's inner surface (radius 0.015 around (0.035, 0, 0) in the xz plane)
  // on the side away from the body, where the outer contour is convex and cannot ask.
  const double voxel = cube.sizes().x() / (1 << kDepth);
  auto on_rim = [&](const Eigen::Vector3d& p) {
    return std::abs(std::hypot(p.x() - 0.035, p.z()) - 0.015) < voxel && p.x() > 0.04 && std::abs(p.y()) < 0.008 + voxel;
  };
  auto finest_on_rim = [&](const Octree& t) {
    std::size_t n = 0;
    t.for_each_leaf([&](const OctreeCell& c) { n += c.depth == kDepth && c.occupied() && on_rim(c.centre); });
    return n;
  };
  const std::size_t with_holes = finest_on_rim(*holes), without = finest_on_rim(*outer);
  cp.occupancy_threshold = 0;  // uniform detail: every rim voxel the carve keeps is at the finest level
  cp.curvature_threshold = -INFINITY;
  const std::size_t uniform = finest_on_rim(*carve(with.silhouettes));
  ::testing::Test::RecordProperty("finest_rim_leaves_with_holes", std::to_string(with_holes));
  ::testing::Test::RecordProperty("finest_rim_leaves_outer_only", std::to_string(without));
  ::testing::Test::RecordProperty("finest_rim_leaves_uniform", std::to_string(uniform));
  std::printf("finest leaves on the handle hole's rim: %zu with hole contours, %zu outer contour only, %zu uniform\n",
              with_holes, without, uniform);
  ASSERT_GE(uniform, 100u);
  EXPECT_GE(with_holes, 0.95 * double(uniform));  // measured 290 of 293
  EXPECT_LT(10 * without, with_holes);            // measured 0
  EXPECT_GT(holes->node_count, outer->node_count);
}

// Scissors' finger loops, the example of holes that a filled silhouette never carves.
// Measured: voxel IoU 0.389 with holes (the same with exact masks) against 0.290 with the holes
// filled. Twelve views bound an 8 mm plate loosely, hence the low IoU either way.
TEST(ThroughHoles, ScissorsFingerLoopsAreKeptInTheSilhouettesAndCarved) {
  check_through_hole(scissors(), [](const Eigen::Vector3d& p) {
    const double r = std::min(std::hypot(p.x() - kLoopX, p.y() - kLoopY), std::hypot(p.x() - kLoopX, p.y() + kLoopY));
    return r < 0.6 * kLoopInner && std::abs(p.z()) < 0.8 * kHalfThickness;
  });
}
