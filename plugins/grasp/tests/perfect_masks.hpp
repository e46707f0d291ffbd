// Carving a mesh as the grasp tests do: views rendered with their masks taken as the silhouettes
// (a perfect segmentation), carved by the real carver with all its detail from the first view.
#pragma once

#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include <Eigen/Geometry>

#include <fba/types/octree.hpp>

#include "fba/geometry/renderer.hpp"
#include "fba/geometry/viewpoints.hpp"
#include "fba/vision/contour_extraction.hpp"
#include "fba/vision/octree_carver.hpp"

namespace fba::test {

// The views' camera: 320 x 240 pixels, focal 300 pixels, centred.
constexpr int kMaskWidth = 320, kMaskHeight = 240;
constexpr double kMaskFocal = 300;

// The carver of these tests: to `depth`, detail from the first view on (detail_after_views 0), on
// one thread.
inline fba::vision::CarverParams carver_params(int depth) {
  fba::vision::CarverParams p;
  p.max_depth = depth;
  p.detail_after_views = 0;
  p.threads = 1;
  return p;
}

// The model of `mesh` carved in `bounds` to `depth` from each of `poses` (camera to world), frame i
// the view's index. A view whose mask gives no silhouette fails the test and is left out.
inline std::shared_ptr<const fba::Octree> carve_perfect_masks(const fba::TriangleMesh& mesh, const Eigen::AlignedBox3d& bounds,
                                                              const std::vector<Eigen::Isometry3d>& poses, int depth = 6) {
  fba::vision::OctreeCarver carver(carver_params(depth));
  carver.set_bounds(bounds);
  for (std::size_t i = 0; i < poses.size(); ++i) {
    auto frame = std::make_shared<fba::Frame>();
    frame->camera = fba::geometry::make_camera(kMaskWidth, kMaskHeight, kMaskFocal, kMaskFocal, (kMaskWidth - 1) / 2.0,
                                               (kMaskHeight - 1) / 2.0, poses[i]);
    frame->has_pose = true;
    frame->index = int(i);
    const auto rendered = fba::geometry::render(mesh, frame->camera);
    frame->image = rendered.colour;
    const auto r = fba::vision::silhouette_from_mask(rendered.mask, frame);
    EXPECT_TRUE(r.ok()) << "view " << i << ": " << r.error;
    if (r.ok()) carver.add_view(*r.silhouette);
  }
  return carver.snapshot();
}

}  // namespace fba::test
