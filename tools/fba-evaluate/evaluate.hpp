// Model-accuracy evaluation (docs: shared/design/grasp-task.md, "How quality is measured"):
//  * voxel IoU of a model against the true solid voxelisation of the object's mesh at the same
//    resolution, and the count of truly occupied voxels the model lacks (carved away);
//  * re-projection IoU of a model onto each silhouette of an image set;
//  * an end-to-end synthetic run: render a mesh from views over the upper hemisphere, carve with
//    perfect silhouettes (the render masks), and compare.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "fba/geometry/voxelize.hpp"
#include "fba/types/mesh.hpp"
#include "fba/types/silhouette.hpp"
#include "fba/vision/octree_carver.hpp"

namespace fba::evaluate {

struct VoxelComparison {
  std::size_t truth_voxels = 0;
  std::size_t model_voxels = 0;
  std::size_t carved_away = 0;  // truly occupied voxels missing from the model
  double iou = 0;
};

// Both grids must share their layout. With z_min set, both are clipped to the table plane
// first (voxels with centre below z_min dropped): the region under an object standing on a
// table is never seen, so no view can carve it.
VoxelComparison compare_voxels(geometry::VoxelGrid truth, geometry::VoxelGrid model,
                               std::optional<double> z_min);

// A model saved as a mesh (a carved octree's occupied leaves as cubes, PLY) turned into a grid
// of (cube, depth): by lattice flood fill when its faces lie on that lattice, else by ray parity.
geometry::VoxelGrid model_mesh_to_grid(const TriangleMesh& model, const Eigen::AlignedBox3d& cube,
                                       int depth);

// IoU of the model mesh's rendered mask with each silhouette's mask, in the silhouette's camera.
std::vector<double> reprojection_ious(const TriangleMesh& model,
                                      const std::vector<Silhouette>& silhouettes);

struct SyntheticParams {
  int views = 8;
  int depth = 6;
  // Band of the upper hemisphere the views are spread over (Fibonacci spiral, equal area).
  double min_elevation_deg = 0.0;
  double max_elevation_deg = 90.0;
  double margin = 0.05;  // root cube = bounding box made a cube, grown by this fraction per side
  int width = 640, height = 480;
  double focal = 600.0;
  bool table_clip = true;  // table plane at the mesh's lowest point
  int threads = 0;         // carver threads, 0 = all cores
  // The carver's silhouette tolerance, pixels (vision::CarverParams).
  double silhouette_tolerance = vision::CarverParams{}.silhouette_tolerance;
  std::filesystem::path save_dir;  // when set: renders, masks and models are written there
};

struct SyntheticResult {
  std::string mesh;
  std::size_t triangles = 0;
  Eigen::AlignedBox3d cube;
  double camera_distance = 0;
  VoxelComparison voxels;
  std::vector<double> reprojection_iou;  // carved model onto each silhouette (carver's projection)
  double render_ms_mean = 0;
  double carve_ms = 0;
  std::size_t octree_nodes = 0;
};

// Renders the mesh from params.views viewpoints, carves with fba::vision::OctreeCarver using the
// exact render masks as silhouettes, and compares the carved model with the true voxelisation.
// Throws geometry::MeshLoadError for an unreadable mesh.
SyntheticResult evaluate_synthetic(const std::filesystem::path& mesh_path,
                                   const SyntheticParams& params);

// A silhouette for a rendered view: the mask, its outer contour, and a frame with the camera.
Silhouette silhouette_from_render(const cv::Mat& colour, const cv::Mat& mask,
                                  const CameraModel& camera, int index);

// The edges of only one triangle: 0 for a closed surface.
std::size_t boundary_edges(const TriangleMesh& mesh);

// A true object's mesh file, which must be closed: every measure of it (a grasp's volume and
// centre of mass, a model's voxel IoU against its solid) needs its inside, which an open surface
// does not have. Throws geometry::MeshLoadError, or std::invalid_argument naming the file and how
// many boundary edges it has.
TriangleMesh load_closed_mesh(const std::string& path);

}  // namespace fba::evaluate
