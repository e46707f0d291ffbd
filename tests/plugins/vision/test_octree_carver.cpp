#include <array>
#include <cmath>
#include <set>
#include <filesystem>
#include <fstream>
#include <memory>

#include <gtest/gtest.h>

#include "fba/geometry/mesh_io.hpp"
#include "fba/geometry/voxelize.hpp"
#include "fba/vision/contour_extraction.hpp"
#include "fba/vision/image_set.hpp"
#include "fba/vision/octree_carver.hpp"
#include "fba/vision/reference_carve.hpp"
#include "support/temp_dir.hpp"

using namespace fba::vision;

namespace {

const std::string kDino = std::string(FBA_SHARED_DATA_DIR) + "/middlebury-dino";
const Eigen::AlignedBox3d kDinoBox(Eigen::Vector3d(-0.061897, -0.018874, -0.057845),
                                   Eigen::Vector3d(0.010897, 0.068227, 0.015495));

// The 15 good dino views, silhouettes by the README recipe; loaded once.
const std::vector<fba::Silhouette>& dino() {
  static const std::vector<fba::Silhouette> views = [] {
    const ImageSet set = ImageSet::load(kDino + "/dinoSR_par.txt");
    std::vector<fba::Silhouette> out;
    for (std::size_t i = 0; i < set.size(); ++i) {
      const ExtractionResult r = extract_silhouette(std::make_shared<const fba::Frame>(set.load_frame(i)));
      if (!r.ok()) throw std::runtime_error(r.error);
      out.push_back(*r.silhouette);
    }
    return out;
  }();
  return views;
}

std::shared_ptr<const fba::Octree> fast_carve(const std::vector<fba::Silhouette>& views, const Eigen::AlignedBox3d& box,
                                              const CarverParams& p, const fba::RegionsOfInterest& roi = {}) {
  OctreeCarver c(p);
  c.set_regions_of_interest(roi);
  c.set_bounds(box);
  c.add_views(views);
  return c.snapshot();
}

std::size_t mismatches_both_ways(const fba::Octree& a, const fba::Octree& b) {
  return count_leaf_mismatches(a, b) + count_leaf_mismatches(b, a);
}

// A camera at `eye` looking at the origin, f = 600 px, 640x480.
fba::CameraModel look_at(const Eigen::Vector3d& eye) {
  fba::CameraModel cam;
  cam.width = 640, cam.height = 480;
  cam.K << 600, 0, 319.5, 0, 600, 239.5, 0, 0, 1;
  const Eigen::Vector3d z = (-eye).normalized();
  Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ());
  if (x.norm() < 1e-6) x = Eigen::Vector3d::UnitX();
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Isometry3d world_from_camera = Eigen::Isometry3d::Identity();
  world_from_camera.linear() << x, y, z;
  world_from_camera.translation() = eye;
  cam.camera_from_world = world_from_camera.inverse();
  return cam;
}

// A perfect silhouette of a sphere: every pixel whose square can touch the sphere's outline.
fba::Silhouette sphere_view(const fba::CameraModel& cam, const Eigen::Vector3d& centre, double radius) {
  auto frame = std::make_shared<fba::Frame>();
  frame->camera = cam;
  fba::Silhouette s;
  s.mask = cv::Mat::zeros(cam.height, cam.width, CV_8UC1);
  const Eigen::Vector3d c = cam.camera_from_world * centre;
  const double margin = c.norm() * 0.75 / cam.K(0, 0);  // half a pixel diagonal at the centre's depth
  const Eigen::Matrix3d Kinv = cam.K.inverse();
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u) {
      const Eigen::Vector3d d = (Kinv * Eigen::Vector3d(u, v, 1)).normalized();
      if ((c - c.dot(d) * d).norm() <= radius + margin) s.mask.at<std::uint8_t>(v, u) = 255;
    }
  s.frame = frame;
  return s;
}

const fba::OctreeNode* leaf_at(const fba::Octree& t, const Eigen::Vector3d& p) {
  const fba::OctreeNode* n = &t.nodes[0];
  while (!n->is_leaf()) {
    const Eigen::Vector3f c = n->centre;
    n = &t.nodes[static_cast<std::size_t>(n->first_child + (p.x() >= c.x() ? 1 : 0) + (p.y() >= c.y() ? 2 : 0) +
                                          (p.z() >= c.z() ? 4 : 0))];
  }
  return n;
}

bool boxes_intersect(const fba::OctreeNode& n, const Eigen::AlignedBox3d& b) {
  const Eigen::Vector3d h = Eigen::Vector3d::Constant(n.half_size);
  return Eigen::AlignedBox3d(n.centre.cast<double>() - h, n.centre.cast<double>() + h).intersects(b);
}

}  // namespace

TEST(CarverVsReference, IdenticalLeafClassificationOnDinoDepth6) {
  for (double tolerance : {0.0, CarverParams{}.silhouette_tolerance, 2.0}) {
    CarverParams p;
    p.max_depth = 6;
    p.silhouette_tolerance = tolerance;
    CarveStats rs;
    const fba::Octree ref = reference_carve(dino(), kDinoBox, p, {}, &rs);
    const auto fast = fast_carve(dino(), kDinoBox, p);
    EXPECT_EQ(mismatches_both_ways(ref, *fast), 0u) << "tolerance " << tolerance;
    EXPECT_EQ(ref.nodes.size(), fast->nodes.size());
    // Not a trivial tree: much was carved and much was kept.
    std::size_t empty = 0;
    for (const auto& n : ref.nodes) empty += n.state == fba::NodeState::Empty ? 1 : 0;
    EXPECT_GT(occupied_leaves(ref).size(), 1000u);
    EXPECT_GT(empty, 1000u);
  }
}

TEST(CarverVsReference, IdenticalWithOccupancyThresholdAndCurvatureCriterion) {
  CarverParams p;
  p.max_depth = 5;
  p.occupancy_threshold = 0.6;
  p.curvature_threshold = 0.0;  // refine where the contour is concave or flat enough
  const fba::Octree ref = reference_carve(dino(), kDinoBox, p);
  const auto fast = fast_carve(dino(), kDinoBox, p);
  EXPECT_EQ(mismatches_both_ways(ref, *fast), 0u);
  // The curvature criterion made some refinement happen that the generic one alone did not.
  std::size_t grasp_splits = 0;
  for (const auto& n : fast->nodes) grasp_splits += n.interest > 0 ? 1 : 0;
  EXPECT_GT(grasp_splits, 0u);
}

TEST(ConservativeCarve, SphereWithPerfectSilhouettesKeepsEveryVoxelWhoseCentreIsInside) {
  const Eigen::Vector3d centre(0.01, -0.005, 0.02);
  const double radius = 0.05;
  std::vector<fba::Silhouette> views;
  for (int i = 0; i < 8; ++i) {
    const double a = i * M_PI / 4, elev = (i % 2 ? 0.5 : -0.3);
    views.push_back(sphere_view(
        look_at(centre + 0.4 * Eigen::Vector3d(std::cos(a) * std::cos(elev), std::sin(a) * std::cos(elev), std::sin(elev))),
        centre, radius));
  }
  const Eigen::AlignedBox3d box(centre - Eigen::Vector3d::Constant(0.07), centre + Eigen::Vector3d::Constant(0.07));
  for (double tolerance : {0.0, CarverParams{}.silhouette_tolerance}) {
    CarverParams p;
    p.max_depth = 6;
    p.silhouette_tolerance = tolerance;
    const auto t = fast_carve(views, box, p);
    // Every cell of the depth-6 grid whose centre is inside the sphere is in an occupied leaf.
    const int n = 1 << p.max_depth;
    const Eigen::Vector3d lo = t->bounds.min();
    const double cell = t->bounds.sizes().x() / n;
    std::size_t inside = 0, carved = 0;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        for (int k = 0; k < n; ++k) {
          const Eigen::Vector3d c = lo + cell * Eigen::Vector3d(i + 0.5, j + 0.5, k + 0.5);
          if ((c - centre).norm() >= radius) continue;
          ++inside;
          carved += leaf_at(*t, c)->state == fba::NodeState::Empty ? 1 : 0;
        }
    EXPECT_GT(inside, 10000u);
    EXPECT_EQ(carved, 0u) << "tolerance " << tolerance;
    // And the carve did carve: the kept volume is within 1.6x the sphere's.
    double volume = 0;
    for (const auto& b : occupied_leaves(*t)) volume += b.volume();
    EXPECT_LT(volume, 1.6 * 4.0 / 3.0 * M_PI * radius * radius * radius) << "tolerance " << tolerance;
  }
}

TEST(PartlyOutsideImage, NodeIsNotCarvedByThatView) {
  // One camera at the origin looking along +z; the silhouette is all background.
  auto frame = std::make_shared<fba::Frame>();
  frame->camera.width = 100, frame->camera.height = 100;
  frame->camera.K << 100, 0, 50, 0, 100, 50, 0, 0, 1;
  fba::Silhouette s;
  s.mask = cv::Mat::zeros(100, 100, CV_8UC1);
  s.frame = frame;
  const Eigen::Vector3d h = Eigen::Vector3d::Constant(0.1);
  for (double tolerance : {0.0, CarverParams{}.silhouette_tolerance}) {
    CarverParams p;
    p.max_depth = 2;
    p.silhouette_tolerance = tolerance;
    // Wholly inside the image (projects to about 39..61 px): carved.
    const Eigen::Vector3d inside(0, 0, 1);
    EXPECT_EQ(fast_carve({s}, {inside - h, inside + h}, p)->nodes[0].state, fba::NodeState::Empty);
    EXPECT_EQ(reference_carve({s}, {inside - h, inside + h}, p).nodes[0].state, fba::NodeState::Empty);
    // Straddling the left border (about -11..11 px): not carved, even by the leaf test.
    const Eigen::Vector3d border(-0.5, 0, 1);
    const auto t = fast_carve({s}, {border - h, border + h}, p);
    EXPECT_NE(t->nodes[0].state, fba::NodeState::Empty) << "tolerance " << tolerance;
    const fba::Octree r = reference_carve({s}, {border - h, border + h}, p);
    EXPECT_NE(r.nodes[0].state, fba::NodeState::Empty);
    // Its children wholly inside the image were carved, those straddling the border kept.
    std::size_t kept = occupied_leaves(*t).size();
    EXPECT_GT(kept, 0u);
    EXPECT_LT(kept, 64u);
  }
}

TEST(IncrementalCarve, AddingViewsOneByOneEqualsTheBatchResult) {
  struct Case {
    double occupancy_threshold;
    double tolerance;
    fba::RegionsOfInterest roi;
  };
  fba::RegionsOfInterest roi;
  roi.boxes.emplace_back(Eigen::Vector3d(-0.03, 0.0, -0.03), Eigen::Vector3d(0.0, 0.03, 0.0));
  const double tol = CarverParams{}.silhouette_tolerance;
  for (const Case& c : {Case{0.0, 0.0, {}}, Case{0.0, tol, {}}, Case{0.7, tol, roi}}) {
    CarverParams p;
    p.max_depth = 6;
    p.occupancy_threshold = c.occupancy_threshold;
    p.silhouette_tolerance = c.tolerance;
    OctreeCarver inc(p);
    inc.set_bounds(kDinoBox);
    inc.set_regions_of_interest(c.roi);
    std::size_t previous_empty = 0;
    for (const auto& v : dino()) {
      inc.add_view(v);
      // Carved nodes stay carved: the carved volume never shrinks.
      std::size_t empty = 0;
      for (const auto& n : inc.snapshot()->nodes) empty += n.state == fba::NodeState::Empty ? 1u << (3 * (6 - n.depth)) : 0;
      EXPECT_GE(empty, previous_empty) << "threshold " << c.occupancy_threshold << ", tolerance " << c.tolerance;
      previous_empty = empty;
    }
    const fba::Octree batch = reference_carve(dino(), kDinoBox, p, c.roi);
    EXPECT_EQ(mismatches_both_ways(*inc.snapshot(), batch), 0u) << "threshold " << c.occupancy_threshold;
    EXPECT_EQ(inc.snapshot()->views, 15);
    EXPECT_EQ(inc.stats().views, 15u);
  }
}

TEST(RoiCriterion, RefinesOnlyNodesThatIntersectTheRegion) {
  CarverParams p;
  p.max_depth = 6;
  p.occupancy_threshold = 1.0;  // the generic criterion never asks
  fba::RegionsOfInterest roi;
  const Eigen::AlignedBox3d region(Eigen::Vector3d(-0.02, 0.02, -0.02), Eigen::Vector3d(-0.01, 0.03, -0.01));
  roi.boxes.push_back(region);
  OctreeCarver carver(p);
  carver.set_bounds(kDinoBox);
  carver.add_views(dino());
  EXPECT_EQ(carver.snapshot()->nodes.size(), 1u);  // without regions nothing is refined
  carver.set_regions_of_interest(roi);
  const auto t = carver.snapshot();
  std::size_t splits = 0, deepest = 0;
  for (const auto& n : t->nodes) {
    if (!n.is_leaf()) {
      ++splits;
      EXPECT_TRUE(boxes_intersect(n, region));
      EXPECT_EQ(n.interest, 1.0f);
    }
    deepest = std::max<std::size_t>(deepest, n.depth);
  }
  EXPECT_GT(splits, 6u);
  EXPECT_EQ(deepest, 6u);
  EXPECT_EQ(mismatches_both_ways(*t, reference_carve(dino(), kDinoBox, p, roi)), 0u);
  // Taking the region away collapses the refinement again.
  carver.set_regions_of_interest({});
  EXPECT_EQ(carver.snapshot()->nodes.size(), 1u);
}

// The target, with the default (conservative) leaf test. At depth 8 the model reaches
// mean 0.978: a finest voxel projects to ~2 px, and the model's outline lies up to half a voxel
// plus the tolerance outside the silhouette; depth 9 halves the voxel. Under the sanitizers, which
// make a depth-9 carve take minutes, the same check runs at depth 7 with the mean that depth
// reaches (measured: mean 0.9701, min 0.9541); the full targets stay with the plain build.
#if FBA_TEST_SANITIZED
constexpr int kDinoDepth = 7;
constexpr double kDinoMeanIoU = 0.965, kDinoMinIoU = 0.95;
#else
constexpr int kDinoDepth = 9;
constexpr double kDinoMeanIoU = 0.98, kDinoMinIoU = 0.95;
#endif

TEST(DinoReprojection, IoUTargetsMetAtTheTestDepth) {
  CarverParams p;
  p.max_depth = kDinoDepth;
  const auto t = fast_carve(dino(), kDinoBox, p);
  double sum = 0, lo = 1;
  for (const auto& v : dino()) {
    const double iou = mask_iou(reproject_mask(*t, v.frame->camera), v.mask);
    sum += iou, lo = std::min(lo, iou);
  }
  RecordProperty("reprojection_iou_mean", std::to_string(sum / dino().size()));
  RecordProperty("reprojection_iou_min", std::to_string(lo));
  EXPECT_GE(sum / dino().size(), kDinoMeanIoU);
  EXPECT_GE(lo, kDinoMinIoU);
}

TEST(Bounds, EstimatedFromViewingConesContainsTheDino) {
  const Eigen::AlignedBox3d est = OctreeCarver::estimate_bounds(dino(), 0.0);
  const Eigen::Vector3d tol = Eigen::Vector3d::Constant(0.002);
  EXPECT_TRUE((est.min().array() <= (kDinoBox.min() + tol).array()).all()) << est.min().transpose();
  EXPECT_TRUE((est.max().array() >= (kDinoBox.max() - tol).array()).all()) << est.max().transpose();
  EXPECT_TRUE((est.sizes().array() < 2.0 * kDinoBox.sizes().array()).all()) << est.sizes().transpose();
  EXPECT_THROW(OctreeCarver::estimate_bounds({dino()[0]}), std::invalid_argument);
  const Eigen::AlignedBox3d cube = fba::geometry::cube_around(kDinoBox);
  EXPECT_NEAR(cube.sizes().x(), cube.sizes().z(), 1e-15);
  EXPECT_TRUE(cube.contains(kDinoBox));
}

TEST(OctreeOutput, SurfaceMeshPlyAndReprojectionOfOneCube) {
  fba::Octree t;
  t.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(-0.1, -0.1, 0.9), Eigen::Vector3d(0.1, 0.1, 1.1));
  fba::OctreeNode root;
  root.centre = Eigen::Vector3f(0, 0, 1);
  root.half_size = 0.1f;
  root.state = fba::NodeState::Full;
  t.nodes.push_back(root);
  const fba::TriangleMesh mesh = occupied_surface_mesh(t);
  EXPECT_EQ(mesh.triangles.size(), 12u);
  // Outward winding: every triangle's normal points away from the cube's centre.
  for (const auto& tri : mesh.triangles) {
    const Eigen::Vector3f a = mesh.vertices[tri[0]], b = mesh.vertices[tri[1]], c = mesh.vertices[tri[2]];
    EXPECT_GT((b - a).cross(c - a).dot((a + b + c) / 3 - root.centre), 0);
  }
  const fba::test::TempDir dir;
  const std::string ply = dir.file("cube.ply");
  write_ply(t, ply);
  std::ifstream in(ply);
  std::string first;
  std::getline(in, first);
  EXPECT_EQ(first, "ply");
  // Seen from the origin along +z the cube's front face spans +-0.1/0.9 * f.
  fba::CameraModel cam;
  cam.width = cam.height = 101;
  cam.K << 100, 0, 50, 0, 100, 50, 0, 0, 1;
  const cv::Mat m = reproject_mask(t, cam);
  const double side = 2 * 100 * 0.1 / 0.9;
  EXPECT_NEAR(cv::countNonZero(m), side * side, 4 * side);
  EXPECT_DOUBLE_EQ(mask_iou(m, m), 1.0);
  EXPECT_DOUBLE_EQ(mask_iou(m, cv::Mat::zeros(m.size(), CV_8UC1)), 0.0);
}

TEST(CarverParams, ToleranceMustBeNonNegative) {
  CarverParams p;
  p.silhouette_tolerance = -0.1;
  EXPECT_THROW(OctreeCarver{p}, std::invalid_argument);
  EXPECT_THROW(reference_carve(dino(), kDinoBox, p), std::invalid_argument);
}

namespace {

// A depth-2 tree over the cube [0, 2]^3: the root's 8 children are Full except child 0, which is
// split into 8 Full leaves but one, grandchild 1 (x in [0.5, 1], y and z in [0, 0.5]), Empty. That
// leaf touches child 1's face x = 1 and the root's faces y = 0 and z = 0: a notch.
fba::Octree notched_cube() {
  fba::Octree t;
  t.bounds = Eigen::AlignedBox3d(Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(2));
  t.max_depth = 2;
  auto node = [](const Eigen::Vector3f& centre, float half, int depth, fba::NodeState state) {
    fba::OctreeNode n;
    n.centre = centre, n.half_size = half, n.depth = static_cast<std::uint8_t>(depth), n.state = state;
    return n;
  };
  auto offset = [](int c, float h) { return Eigen::Vector3f(c & 1 ? h : -h, c & 2 ? h : -h, c & 4 ? h : -h); };
  t.nodes.push_back(node(Eigen::Vector3f::Ones(), 1, 0, fba::NodeState::Partial));
  t.nodes[0].first_child = 1;
  for (int c = 0; c < 8; ++c) t.nodes.push_back(node(Eigen::Vector3f::Ones() + offset(c, 0.5f), 0.5f, 1, fba::NodeState::Full));
  t.nodes[1].state = fba::NodeState::Partial;
  t.nodes[1].first_child = 9;
  for (int c = 0; c < 8; ++c)
    t.nodes.push_back(node(t.nodes[1].centre + offset(c, 0.25f), 0.25f, 2, c == 1 ? fba::NodeState::Empty : fba::NodeState::Full));
  return t;
}

}  // namespace

TEST(OctreeOutput, SurfaceMeshHasOnlyFacesBetweenOccupiedAndFreeSpace) {
  const fba::Octree t = notched_cube();
  const fba::TriangleMesh mesh = occupied_surface_mesh(t);
  const fba::geometry::VoxelGrid grid = fba::geometry::rasterize_octree(t);  // 4^3, voxel 0.5
  auto occupied_at = [&](const Eigen::Vector3f& p) {
    const Eigen::Vector3d q = p.cast<double>() / grid.voxel_size();
    const int i = static_cast<int>(std::floor(q.x())), j = static_cast<int>(std::floor(q.y())), k = static_cast<int>(std::floor(q.z()));
    return i >= 0 && j >= 0 && k >= 0 && i < grid.n && j < grid.n && k < grid.n && grid.occupied(i, j, k);
  };
  double area = 0;
  for (const auto& tri : mesh.triangles) {
    const Eigen::Vector3f a = mesh.vertices[tri[0]], b = mesh.vertices[tri[1]], c = mesh.vertices[tri[2]];
    const Eigen::Vector3f n = (b - a).cross(c - a);
    area += 0.5 * n.norm();
    const Eigen::Vector3f mid = (a + b + c) / 3, step = 0.1f * n.normalized();
    EXPECT_TRUE(occupied_at(mid - step)) << "inside of a face is not occupied at " << mid.transpose();
    EXPECT_FALSE(occupied_at(mid + step)) << "a face inside the model at " << mid.transpose();
  }
  // The cube's surface (24) minus the notch's two openings, plus its four walls (0.25 each).
  EXPECT_NEAR(area, 24 - 2 * 0.25 + 4 * 0.25, 1e-5);
  // Welded: no two vertices at the same place.
  std::set<std::array<float, 3>> distinct;
  for (const auto& v : mesh.vertices) distinct.insert({v.x(), v.y(), v.z()});
  EXPECT_EQ(distinct.size(), mesh.vertices.size());
  // Closed around the model: the lattice flood fill gives back the occupied leaves.
  const auto filled = fba::geometry::voxelize_lattice_surface(mesh, t.bounds, t.max_depth);
  EXPECT_EQ(filled.occupancy, grid.occupancy);
}

TEST(OctreeOutput, SurfaceMeshOfTheCarvedDinoEnclosesExactlyTheOccupiedLeaves) {
  CarverParams p;
  p.max_depth = 6;
  const auto t = fast_carve(dino(), kDinoBox, p);
  const fba::TriangleMesh mesh = occupied_surface_mesh(*t);
  const auto grid = fba::geometry::rasterize_octree(*t);
  EXPECT_EQ(fba::geometry::voxelize_lattice_surface(mesh, t->bounds, p.max_depth).occupancy, grid.occupancy);
  // A large leaf's face is one square, not one per finest voxel.
  EXPECT_LE(mesh.triangles.size(), fba::geometry::grid_to_mesh(grid).triangles.size());
}
