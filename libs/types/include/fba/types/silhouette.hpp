// The target's outline in one image.
#pragma once

#include <memory>
#include <vector>

#include <opencv2/core.hpp>

#include "fba/data_type.hpp"
#include "fba/types/frame.hpp"

namespace fba {

// One closed boundary of the object (its outer contour or a hole's), resampled every pixel of arc
// length and described point by point. Every vector has contour.size() entries, except
// metric_curvature, which is empty when the object's depth in this frame is unknown.
// Directions follow the image axes (x right, y down). The tangent, normal and curvature are those
// of the outline smoothed along the arc with a Gaussian of the extraction's curvature scale (so a
// staircase of pixels is a smooth curve); the points are on the outline smoothed only over 1 px
// (which takes out the pixel chain's zigzag), within half a pixel of the mask's edge.
// Sign convention, the same for holes: the normal points out of the object (away from the object
// on the outer contour, into the hole on a hole's), and the curvature is positive where the
// object is convex there (bulges towards the normal), negative where concave. A disc of radius r
// has +1/r everywhere, a round hole of radius r has -1/r, a straight edge 0.
struct Outline {
  std::vector<cv::Point2d> contour;     // image pixels (pixel centres at integer coordinates)
  std::vector<cv::Point2d> tangents;    // unit, in the contour's direction
  std::vector<cv::Point2d> normals;     // unit, out of the object
  std::vector<double> curvature;        // signed, 1/pixel
  // Signed, 1/m: the curvature of the outline carried to the object's depth in this view
  // (curvature * focal length / depth), so it compares with the object's size in metres. Empty
  // when the depth is unknown (no depth hint and no object position given to the extraction).
  std::vector<double> metric_curvature;
};

// The target's outer outline (the inherited fields) and its holes.
struct Silhouette : Outline {
  cv::Mat mask;                       // 8-bit, 255 inside the object, 0 outside (and in its holes); image size
  std::vector<Outline> holes;         // the holes left open in the mask, each described as above
  std::shared_ptr<const Frame> frame; // the frame it was extracted from (camera, pose, image)
  bool touches_border = false;        // the target leaves the image on this view
};

}  // namespace fba

FBA_DATA_TYPE(fba::Silhouette, "fba.Silhouette",
              "A target mask with its outer contour and holes, each resampled at 1 px with per-point tangent, outward "
              "normal and signed curvature (1/px, and 1/m when the depth is known), and the source frame.");
