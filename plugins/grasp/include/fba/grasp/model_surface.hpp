// The surface of an octree model as grasp synthesis sees it: one SurfaceSample per occupied leaf
// that has a free (empty, or outside the root box) face neighbour, with an outward normal and a
// mean curvature estimated over its neighbours, and flagged uncertain where the model has not yet
// resolved the boundary to its finest depth.
#pragma once

#include <optional>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "fba/grasp/synthesis.hpp"
#include "fba/types/camera.hpp"
#include "fba/types/octree.hpp"
#include "fba/types/silhouette.hpp"

namespace fba::grasp {

struct ModelSurfaceParams {
  // Metres: the neighbourhood that smooths normals and positions and estimates curvature; 0 means
  // 3 edges of the finest occupied leaf (the staircase of voxel faces needs a few steps to average).
  double radius = 0;
  // World z of the table the object rests on, when known. Carving keeps what no view saw, as
  // nothing there was seen to be empty: space out of every image (often above the object, at the
  // top of the root box) and the silhouettes' cones under the table. With a table, only the leaves
  // joined through shared faces to one that stands on it (its bottom within one of its edges of the
  // table: a sphere's lowest leaf may stand that high) are the object, and only above it.
  std::optional<double> table_z;
  ParallelFor parallel_for;  // the leaves' faces, the normals' fits and the neighbourhoods
};

struct ModelSurface {
  std::vector<SurfaceSample> samples;
  double radius = 0;          // the neighbourhood used (pass it on as SynthesisParams::neighbour_radius)
  double finest_edge = 0;     // edge of the finest occupied leaf, metres (0 when there is none)
  std::size_t leaves = 0;     // occupied leaves in the model
  std::size_t unsupported_leaves = 0;  // of those, left out as not joined to the table (ModelSurfaceParams::table_z)
};

// Empty samples for a model with no occupied leaf. Throws std::invalid_argument for a model whose
// root box is not a cube of positive size, or a negative radius.
//
// Position: the leaf's centre moved to its free faces (a face centre, an edge or a corner of the
// voxel), then projected on the plane fitted through its neighbours. Normal: the smallest
// principal axis of the neighbours' positions, oriented like the summed free-face directions
// (those alone if the fit has too few points). Uncertain: the leaf is partial (it straddles the
// object's boundary in some view) and coarser than the model's max_depth, so the carver has not
// resolved this part of the surface yet. A full leaf next to an empty one is certain at any
// depth: every view has it inside, and the face between them is where a view cut the object.
ModelSurface model_surface(const Octree& model, const ModelSurfaceParams& params = {});

// What a posed silhouette says about the surface: its rim, the outline points where the line of
// sight grazes the object (a point where the outline meets the image's border is where the image
// cuts the object off, not a rim), each with the outward normal of the cone of sight there.
struct SilhouetteRim {
  CameraModel camera;                     // an ideal pinhole: the silhouette's frame is undistorted
  std::vector<Eigen::Vector2d> points;    // image pixels
  std::vector<Eigen::Vector3d> normals;   // world, unit: the tangent plane of the cone of sight through the eye and the point
};

// The rim of a silhouette whose frame has a pose: its outer contour and holes, less the points
// within 1.5 px of the image's border. Throws std::invalid_argument for a silhouette with no
// frame, an unposed frame, or a camera with lens distortion.
SilhouetteRim silhouette_rim(const Silhouette& silhouette);

// Flags as unpinned the samples that no pair of views pins down. A silhouette fixes the surface
// only on its rim, where the line of sight grazes the object; elsewhere a carved model is the
// intersection of the views' cones and may lie centimetres off the object: from three views on one
// side of a can, the model's far side is a wedge whose faces touch the can on one line each.
// A view's rim passes through a sample when the sample projects within `tolerance` (metres at its
// depth, plus a pixel) of the rim and the line of sight lies within rim_deg of the sample's
// tangent plane. Two such views pin the sample when their lines of sight are at least
// separation_deg apart and their cones' tangent planes there agree within rim_deg: two cones also
// cross along edges of the model that neither touches the object on (their planes meet at an angle
// there), and touch the object together only where both are tangent to it. Throws
// std::invalid_argument for angles out of (0, 90) or a negative tolerance.
void mark_unobserved(std::span<SurfaceSample> samples, std::span<const SilhouetteRim> views, double tolerance, double rim_deg = 15,
                     double separation_deg = 20);

}  // namespace fba::grasp
