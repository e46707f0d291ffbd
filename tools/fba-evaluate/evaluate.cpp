#include "evaluate.hpp"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "fba/geometry/mesh_io.hpp"
#include "fba/geometry/renderer.hpp"
#include "fba/geometry/viewpoints.hpp"
#include "fba/vision/caption.hpp"
#include "fba/vision/model_picture.hpp"
#include "fba/vision/octree_carver.hpp"

namespace fba::evaluate {

using Clock = std::chrono::steady_clock;

static double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// A view's render and its mask, each captioned with the view and where its camera stood.
static void save_view(const std::filesystem::path& stem, const std::string& object, std::size_t i,
                      const geometry::RenderResult& r, const CameraModel& camera) {
  const Eigen::Vector3d eye = camera.centre_in_world();
  vision::Caption caption;
  caption.details = "camera at " + vision::position_text(eye.x(), eye.y(), eye.z()) + ", looking at the object";
  caption.title = object + ": view " + std::to_string(i + 1) + ", rendered";
  caption.legend = {{{70, 150, 230}, "the object, shaded", vision::LegendMark::Swatch}};
  cv::imwrite(stem.string() + "_view" + std::to_string(i) + ".png", vision::captioned(r.colour, caption));
  caption.title = object + ": view " + std::to_string(i + 1) + ", its silhouette";
  caption.legend = {{{255, 255, 255}, "the object's silhouette, carved from", vision::LegendMark::Swatch}};
  cv::imwrite(stem.string() + "_mask" + std::to_string(i) + ".png", vision::captioned(r.mask, caption));
}

VoxelComparison compare_voxels(geometry::VoxelGrid truth, geometry::VoxelGrid model,
                               std::optional<double> z_min) {
  if (z_min) {
    geometry::clip_below(truth, *z_min);
    geometry::clip_below(model, *z_min);
  }
  VoxelComparison c;
  c.truth_voxels = truth.count();
  c.model_voxels = model.count();
  c.carved_away = geometry::carved_away(truth, model);
  c.iou = geometry::iou(truth, model);
  return c;
}

geometry::VoxelGrid model_mesh_to_grid(const TriangleMesh& model, const Eigen::AlignedBox3d& cube,
                                       int depth) {
  try {
    return geometry::voxelize_lattice_surface(model, cube, depth);
  } catch (const std::invalid_argument&) {
    // Not a lattice model (e.g. a smooth mesh): treat it as a closed surface.
    return geometry::voxelize(model, cube, depth);
  }
}

std::vector<double> reprojection_ious(const TriangleMesh& model,
                                      const std::vector<Silhouette>& silhouettes) {
  std::vector<double> ious;
  for (const auto& s : silhouettes) {
    if (!s.frame) throw std::invalid_argument("reprojection_ious: silhouette without a frame");
    const geometry::RenderResult r = geometry::render(model, s.frame->camera);
    ious.push_back(vision::mask_iou(r.mask, s.mask));
  }
  return ious;
}

Silhouette silhouette_from_render(const cv::Mat& colour, const cv::Mat& mask,
                                  const CameraModel& camera, int index) {
  auto frame = std::make_shared<Frame>();
  frame->image = colour;
  frame->camera = camera;
  frame->has_pose = true;
  frame->source = "sim";
  frame->index = index;
  Silhouette s;
  s.mask = mask;
  s.frame = frame;
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(mask.clone(), contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  std::size_t best = 0;
  for (std::size_t i = 1; i < contours.size(); ++i)
    if (cv::contourArea(contours[i]) > cv::contourArea(contours[best])) best = i;
  if (!contours.empty()) s.contour.assign(contours[best].begin(), contours[best].end());
  // Border contact: any mask pixel on the first or last row or column.
  s.touches_border = cv::countNonZero(mask.row(0)) + cv::countNonZero(mask.row(mask.rows - 1)) +
                         cv::countNonZero(mask.col(0)) + cv::countNonZero(mask.col(mask.cols - 1)) >
                     0;
  return s;
}

std::size_t boundary_edges(const TriangleMesh& mesh) {
  // Each edge as its two vertex indices, smaller first; an edge that occurs once is on a boundary.
  std::vector<std::uint64_t> edges;
  edges.reserve(3 * mesh.triangles.size());
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const auto a = static_cast<std::uint32_t>(t[k]), b = static_cast<std::uint32_t>(t[(k + 1) % 3]);
      edges.push_back(std::uint64_t{std::min(a, b)} << 32 | std::max(a, b));
    }
  std::sort(edges.begin(), edges.end());
  std::size_t once = 0;
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i + 1;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    once += j - i == 1;
    i = j;
  }
  return once;
}

TriangleMesh load_closed_mesh(const std::string& path) {
  TriangleMesh m = geometry::load_mesh(path);
  if (const std::size_t open = boundary_edges(m))
    throw std::invalid_argument("mesh '" + path + "': expected a closed surface (what is measured is inside it: the volume and centre of mass of a grasp's object, the voxels of a model's truth); found " +
                                std::to_string(open) + " boundary edge" + (open == 1 ? "" : "s") + " (edges of one triangle only)");
  return m;
}

SyntheticResult evaluate_synthetic(const std::filesystem::path& mesh_path,
                                   const SyntheticParams& p) {
  SyntheticResult out;
  out.mesh = mesh_path.string();
  const TriangleMesh mesh = load_closed_mesh(mesh_path.string());
  out.triangles = mesh.triangles.size();
  const Eigen::AlignedBox3d box = geometry::mesh_bounds(mesh);
  out.cube = geometry::cube_around(box, p.margin);

  // The camera frames the object, as an exploring camera would: far enough that the sphere
  // around the object's bounding box fits in the image from any direction, with 5% to spare.
  // Framing the root cube instead (its circumscribed sphere, ~1.6x farther for the elongated
  // objects) wastes resolution on the carving margin. Parts of that margin may leave some images;
  // the carver never carves a node partly outside a view on that view's evidence, so this costs
  // no safety, only leaves such nodes to the other views.
  out.camera_distance = fba::geometry::framing_distance(box, p.width, p.height, p.focal);
  constexpr double deg = std::numbers::pi / 180;
  const auto poses =
      geometry::hemisphere_views(p.views, p.min_elevation_deg * deg, p.max_elevation_deg * deg,
                                 out.camera_distance, out.cube.center());

  if (!p.save_dir.empty()) std::filesystem::create_directories(p.save_dir);
  const std::string stem = mesh_path.parent_path().filename().string() + "_" +
                           mesh_path.stem().string();
  const std::string object = vision::object_name(mesh_path.string());

  std::vector<Silhouette> silhouettes;
  double render_ms = 0;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const CameraModel cam = geometry::make_camera(p.width, p.height, p.focal, p.focal,
                                                  (p.width - 1) / 2.0, (p.height - 1) / 2.0, poses[i]);
    const auto t0 = Clock::now();
    const geometry::RenderResult r = geometry::render(mesh, cam);
    render_ms += ms_since(t0);
    silhouettes.push_back(silhouette_from_render(r.colour, r.mask, cam, static_cast<int>(i)));
    if (!p.save_dir.empty()) save_view(p.save_dir / stem, object, i, r, cam);
  }
  out.render_ms_mean = poses.empty() ? 0 : render_ms / poses.size();

  vision::CarverParams cp;
  cp.max_depth = p.depth;
  cp.threads = p.threads;
  cp.silhouette_tolerance = p.silhouette_tolerance;
  cp.detail_after_views = std::min(cp.detail_after_views, p.views);  // full detail with all the views there are
  vision::OctreeCarver carver(cp);
  carver.set_bounds(out.cube);
  const auto t0 = Clock::now();
  for (const auto& s : silhouettes) carver.add_view(s);
  const std::shared_ptr<const Octree> model = carver.snapshot();
  out.carve_ms = ms_since(t0);
  out.octree_nodes = model->node_count;

  // The truth on the carver's own root cube, so both grids share their lattice exactly.
  const geometry::VoxelGrid truth = geometry::voxelize(mesh, model->bounds, p.depth);
  const geometry::VoxelGrid carved = geometry::rasterize_octree(*model);
  std::optional<double> z_min;
  if (p.table_clip) z_min = box.min().z();
  out.voxels = compare_voxels(truth, carved, z_min);

  for (const auto& s : silhouettes)
    out.reprojection_iou.push_back(vision::mask_iou(vision::reproject_mask(*model, s.frame->camera), s.mask));

  if (!p.save_dir.empty()) {
    vision::write_ply(*model, (p.save_dir / (stem + "_carved.ply")).string());
    geometry::write_ply(geometry::grid_to_mesh(truth), p.save_dir / (stem + "_truth_voxels.ply"));
    // The carved model (clipped as evaluated), as a run's model.png shows it.
    vision::ModelPictureOptions look;
    look.object = object;
    for (const auto& s : silhouettes) look.views.push_back(s.frame->camera);
    look.table_z = z_min;
    cv::imwrite((p.save_dir / (stem + "_carved.png")).string(), vision::model_picture(*model, look));
  }
  return out;
}

}  // namespace fba::evaluate
