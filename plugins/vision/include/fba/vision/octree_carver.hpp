// Octree carving from silhouettes (the paper's Algorithms 1 and 2), incremental and parallel.
//
// The node test, shared with reference_carve() so both classify every leaf identically. It is
// conservative: given perfect silhouettes it never carves a voxel whose centre is inside the
// object. A perfect (rendered) mask holds the pixels whose centre falls in the object's
// continuous silhouette S, so a point of S near the outline may have no mask pixel under it.
// Seeing each pixel as the closed unit square around its centre, and the mask as the union of
// its silhouette squares, the test uses a tolerance tol = silhouette_tolerance (pixels): a
// projection within tol of the mask counts as inside. The default sqrt(2)/2 is the least that
// is safe for any S at least one pixel diagonal wide (each point p of S lies in a disc of radius
// sqrt(2)/2 inside S): the pixel centre nearest to that disc's centre c is within sqrt(2)/2 of
// c, so inside the disc, so in the mask, and its square contains c, which is within sqrt(2)/2
// of p. (0 gives the plain voxel-centre test, which carves true voxels near the outline.)
//  * the node's 8 corners are projected with P = K [R | t] (ideal pinhole: undistort first);
//  * the test rectangle holds the pixels whose square comes within tol of the bounding box of
//    the 8 projections (pixel centres at integer coordinates, so centres within tol + 1/2);
//  * occupancy in a view = (silhouette pixels in the rectangle + rectangle pixels outside the
//    image) / rectangle area, from an integral image in O(1). Pixels outside the image count as
//    occupied because nothing is known there, so a node that is partly outside an image is never
//    carved on that view's evidence; a node with a corner behind the camera has occupancy 1
//    (unknown) in that view. Except (carve_outside_view) for a view whose silhouette lies wholly
//    inside its image: it saw the whole object, so its pixels outside the image count as empty;
//  * a node is Empty when some view gives occupancy 0, Full when every view gives 1, else
//    Partial. Its stored occupancy is the lowest rectangle share over the views (0 when Empty);
//  * the leaf test: a Partial leaf at the resolution limit (max_depth or min_node_size) is Empty
//    when, in some view whose rectangle is inside the image, no silhouette pixel's square lies
//    within tol (Euclidean) of its centre's projection: the classic voxel-centre test made safe
//    against the mask's discretisation, in O(1) (an integral-image window, at most 9 pixels
//    looked at). The finest voxels are thus kept by where their centre projects, not by the
//    whole voxel's projection, which padded the model by about a voxel all round;
//  * a non-empty node is split when depth < max_depth, its edge > min_node_size (and, while fewer
//    than detail_after_views views are in, depth < detail_depth), occupancy < 1
//    in some view (a wholly-inside node's children would all be Full), and either its share in
//    some view where it lies on the outline (neither empty nor full) > occupancy_threshold
//    (generic criterion) or a grasp criterion asks: the node
//    intersects a region of interest, or in some view where it is not wholly inside, its
//    rectangle holds a contour point whose curvature is below curvature_threshold (a region that
//    may be grasped); the points of the holes' contours count as the outer contour's do (a
//    hole's rim is outline too, and with the outward normal pointing into the hole a round hole
//    is concave, so graspable at a threshold of 0). The share is measured over the projected node (the convex hull of its 8
//    projected corners, see hull_share in carve_common.hpp), not its rectangle, so that it does
//    not depend on the viewing angle; a Partial node's share lies strictly between 0 and 1, so
//    threshold 0 splits every Partial node (uniform refinement) and 1 switches the generic
//    criterion off.
//
// The model is a function of (views, regions of interest, parameters): adding views one by one
// gives exactly the batch result; nodes carved stay carved; set_regions_of_interest re-decides
// refinement over the views already in (it refines new regions and collapses regions no longer
// of interest, so memory follows the current interest).
#pragma once

#include <cstddef>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <numbers>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "fba/parallel_for.hpp"
#include "fba/types/camera.hpp"
#include "fba/types/mesh.hpp"
#include "fba/types/octree.hpp"
#include "fba/types/regions_of_interest.hpp"
#include "fba/types/silhouette.hpp"

namespace fba::vision {

struct CarverParams {
  int max_depth = 6;                 // root is depth 0; at most 19
  double min_node_size = 0.0;        // metres: nodes with an edge <= this are not split
  // Generic criterion: split a Partial node whose share, in a view where it lies on the outline,
  // is above this. 0 (default) splits every Partial node (uniform detail); at 0.5 nodes mostly
  // outside the silhouette wherever they meet its outline stay coarse, so that a grasp criterion
  // decides where detail goes; 1 switches it off.
  double occupancy_threshold = 0.0;
  // The generic criterion splits only nodes shallower than this; deeper ones are split only where
  // a grasp criterion asks. The paper's scheme: the generic criterion for the initial analysis,
  // the grasp-specific one for the detail. 19 (default): the generic criterion at every depth.
  int generic_depth = 19;
  // Grasp criterion on the contour: split where a point of the outer or a hole's contour with
  // curvature (1/px, convex > 0) below this falls in the node's rectangle. -infinity (default)
  // switches it off.
  double curvature_threshold = -std::numeric_limits<double>::infinity();
  // Pixels: how far from a projection a silhouette pixel's square still counts (see above).
  // sqrt(2)/2 keeps the carve conservative for perfect masks of silhouettes at least one pixel
  // diagonal wide; larger values allow for masks that are off by more (calibration, segmentation).
  double silhouette_tolerance = std::numbers::sqrt2 / 2;
  // A view whose silhouette lies wholly inside its image (Silhouette::touches_border false) saw
  // the whole object, so whatever projects outside that image is not the object: its pixels
  // outside the image count as empty, not unknown. Space no view covers is otherwise never
  // carved, and such a corner of the workspace stays an obstacle to the arm for the whole run.
  // Off: outside every image is unknown (an object that may extend beyond the views).
  bool carve_outside_view = true;
  // Detail waits for views: while fewer than detail_after_views views are in, nodes at depth >=
  // detail_depth are not split (the model stops at detail_depth). The first silhouettes bound the
  // object only by their viewing cones, whose surface later views mostly carve away; refining it
  // at once made an incremental carve of the 15 dino views at depth 9 visit 4.7 times the nodes of
  // the batch carve when detail waited for 3 views, 1.96 times when it waits for 8. With
  // detail_after_views views or more the rule has no effect, so incremental and batch carves of
  // the same views agree at every step. An owner that knows it will get fewer views lowers it
  // (0 = no wait).
  int detail_after_views = 8;
  int detail_depth = 4;
  int threads = 0;                   // 0 = all cores (ignored when parallel_for is given)
  // The owner's threads (a component: its task's pool); empty: the carver starts `threads`
  // threads of its own per update.
  fba::ParallelFor parallel_for;
  // Bytes the model may use: a max_depth whose worst case (every node of every level, plus the
  // copies that versions still being read hold) exceeds it is refused, and the tree's storage
  // never grows beyond it.
  std::size_t memory_budget = std::size_t(4) << 30;
};

// The worst-case bytes a carve to max_depth may take (see CarverParams::memory_budget).
std::size_t worst_case_bytes(int max_depth);

// The carver's parallel_for when its owner gives none: f(0) .. f(n - 1) on up to `threads`
// threads (this one included). An exception in any f (an allocation failure, the memory budget)
// stops the others at their next index; all threads are joined and the first exception rethrown.
void run_on_threads(unsigned threads, std::size_t n, const std::function<void(std::size_t)>& f);

// One update (add_view, add_views, set_regions_of_interest, set_bounds) and the snapshot after it.
struct ViewStats {
  std::size_t views = 0;            // views in the model after the update
  double carve_seconds = 0;         // wall time of the update
  double snapshot_seconds = 0;      // wall time of publishing the first snapshot() after it
  std::size_t nodes_visited = 0;    // node updates in it
  std::size_t nodes_refined = 0;    // splits in it
  std::size_t blocks_copied = 0;    // blocks of 8 nodes copied because a published version holds them
  std::size_t model_nodes = 0;      // nodes of the model after it
  std::size_t model_bytes = 0;      // their bytes (8 per node)
  std::size_t storage_bytes = 0;    // the carver's whole block storage, old versions' blocks included
};

struct CarveStats {
  std::size_t views = 0;
  std::size_t nodes_visited = 0;  // node updates (a node tested against its pending views)
  std::size_t nodes_refined = 0;  // splits
  double seconds = 0;             // wall time spent carving, summed over calls
  std::vector<ViewStats> updates; // one per update, in order
};

class OctreeCarver {
 public:
  explicit OctreeCarver(CarverParams p);
  ~OctreeCarver();
  OctreeCarver(const OctreeCarver&) = delete;
  OctreeCarver& operator=(const OctreeCarver&) = delete;

  // The root voxel: geometry::cube_around(box), the smallest cube with the box's centre that
  // contains it. Resets the model (views already added are kept and re-applied).
  void set_bounds(const Eigen::AlignedBox3d& box);
  // A box holding the object, from the intersection of the viewing cones of the silhouettes'
  // bounding rectangles (a linear programme); sides of a rectangle on the image border do not
  // constrain. Needs >= 2 silhouettes with frames; throws std::invalid_argument when the cones
  // do not bound a finite region. Grown by `margin` (fraction of the size) on every side.
  static Eigen::AlignedBox3d estimate_bounds(const std::vector<fba::Silhouette>& views, double margin = 0.05);

  // Refines the model with this view: existing nodes are tested against it, new nodes against
  // every view so far. Needs s.frame (the camera) and an 8-bit mask of the camera's size; throws
  // std::invalid_argument otherwise. Before set_bounds the view is only stored.
  void add_view(const fba::Silhouette& s);
  // Several views at once: the same model as adding them one by one, in one pass over the tree.
  void add_views(const std::vector<fba::Silhouette>& views);
  void set_regions_of_interest(const fba::RegionsOfInterest& roi);

  // Immutable, shares the unchanged blocks with the other versions; O(1): the next update copies
  // the blocks it changes instead of writing to them. Cached until the next change.
  std::shared_ptr<const fba::Octree> snapshot() const;
  CarveStats stats() const;
  const CarverParams& params() const { return params_; }

 private:
  struct Impl;
  CarverParams params_;
  std::unique_ptr<Impl> impl_;
  mutable std::mutex mutex_;  // snapshot() and stats() may be called from another thread
};

// Leaves that are Full or Partial, as boxes.
std::vector<Eigen::AlignedBox3d> occupied_leaves(const fba::Octree&);
// The surface of the occupied space (Full and Partial leaves): exactly the squares between an
// occupied leaf and a non-occupied one or the outside of the root, two triangles each, wound
// outward, with shared corners welded. Where a large occupied leaf meets smaller leaves, only the
// parts against non-occupied ones are emitted, so no face lies inside the model.
fba::TriangleMesh occupied_surface_mesh(const fba::Octree&);
// Which occupied leaves a surface holds (true: kept); an empty filter keeps them all.
using LeafFilter = std::function<bool(const fba::OctreeCell&)>;
// The surface of the occupied leaves the filter keeps, built as occupied_surface_mesh builds its
// own: the squares between a kept leaf and one that is not (left out, or not occupied).
fba::TriangleMesh surface_mesh(const fba::Octree&, const LeafFilter& keep);
// The one way to save an octree: occupied_surface_mesh written by geometry::write_ply (binary
// PLY, opens in MeshLab). Throws std::runtime_error on I/O error.
void write_ply(const fba::Octree&, const std::string& path);
// Whether at least two of the views (every one, when fewer are given) see the whole leaf inside
// their image. Elsewhere the model is bounded by one cone of sight at most: nothing there was seen
// to be empty (the top of a root box no camera framed), so it is not carved, however it looks.
bool seen_by_two_views(const fba::OctreeCell& leaf, const std::vector<fba::CameraModel>& views);
// Which occupied leaves a model's PLY holds: Seen, those two views saw (seen_by_two_views: the
// object as the views show it, without the space around it no view could carve); Occupied, all.
enum class PlyLeaves { Seen, Occupied };
// The surface a PLY of these leaves holds (surface_mesh's): write it with geometry::write_ply.
fba::TriangleMesh ply_mesh(const fba::Octree&, PlyLeaves leaves, const std::vector<fba::CameraModel>& views);
// The occupied space seen by the camera (ideal pinhole, 8U 0/255, camera size): a pixel is in
// when its centre sees the model, as geometry::render samples it.
cv::Mat reproject_mask(const fba::Octree&, const fba::CameraModel&);
// Intersection over union of two masks (non-zero = in); 1 when both are empty.
double mask_iou(const cv::Mat& a, const cv::Mat& b);
// Walks both trees together: the number of leaves of `a` whose region is not a leaf of `b` with
// the same state (0 when both classify every leaf identically).
std::size_t count_leaf_mismatches(const fba::Octree& a, const fba::Octree& b);

}  // namespace fba::vision
