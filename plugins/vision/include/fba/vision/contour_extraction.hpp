// The target's silhouette in one image: binarise, clean up, pick the target's contour, and
// describe it (mask with its holes, outer contour and hole contours resampled at 1 px with tangents,
// outward normals and signed curvature, whether it leaves the image).
//
// Errors: extract_silhouette() never throws on bad images; an empty or unusable image, or no
// contour passing the selection, gives an ExtractionResult with ok() false and a message (the
// exploration loop carries on with the next view). Invalid parameters (negative sizes, threshold
// outside 0..1) throw std::invalid_argument, since they are programming errors.
#pragma once

#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "fba/types/frame.hpp"
#include "fba/types/silhouette.hpp"

namespace fba::vision {

struct BinariseParams {
  enum class Method { Fixed, Otsu };
  Method method = Method::Fixed;
  // Fixed: foreground where grey > threshold * full scale (0..1). Otsu ignores it.
  double threshold = 0.19;
  // true when the object is darker than the background.
  bool dark_object = false;
  // Clean-up, in this order: dilate, erode, open, close (each a disc of that radius, pixels,
  // 0 = skip). The Middlebury recipe is threshold 0.19, dilate 10, erode 7: dilating first closes
  // the dark shadow gaps, the smaller erosion leaves the mask slightly grown (conservative).
  int dilate_px = 10;
  int erode_px = 7;
  int open_px = 0;
  int close_px = 0;
};

struct SelectionParams {
  double min_area_px = 200;          // smaller blobs are noise
  double max_area_fraction = 0.95;   // larger blobs (of the image area) are background
  // Prefer the contour containing (or nearest to) this point; default the image centre.
  std::optional<cv::Point2d> near_point;
  // Holes inside the target's outline at least this large (pixels) stay open in the mask and are
  // described in Silhouette::holes; smaller ones are filled (specks of shadow or glare, which
  // would carve away real object). Infinity fills every hole.
  double min_hole_area_px = 50;
  // extract_silhouette only (it has the image): a hole stays open only when it looks like the
  // background, its mean grey within this share of full scale of the mean grey outside the
  // objects; else it is filled. A hole you see through shows the background; a dark shadow or
  // crease on the object (the dino has such holes of up to 1,200 px, 10 to 30 grey levels over a
  // background of 1 to 3) does not. 1 switches the test off.
  double hole_background_tolerance = 0.02;
  // Curvature scale: sigma (pixels of arc length) of the Gaussian that smooths the outline before
  // tangents, normals and curvature are taken (see describe_outline).
  double curvature_scale_px = 20;
  // The object's depth in the frame, for the metric curvature (1/m): depth_m when > 0, else the
  // camera z of object_centre (world, metres) when it is given and the frame has a pose. With
  // neither, metric_curvature stays empty.
  double depth_m = 0;
  std::optional<Eigen::Vector3d> object_centre;
};

struct ExtractionParams {
  BinariseParams binarise;
  SelectionParams selection;
};

struct ExtractionResult {
  std::optional<fba::Silhouette> silhouette;
  std::string error;  // why there is no silhouette; empty on success
  bool ok() const { return silhouette.has_value(); }
};

// 8-bit 0/255 mask of the foreground after thresholding and the clean-up. Accepts 8-bit or
// 16-bit, grey or BGR(A); colour is converted to grey. Throws std::invalid_argument on an empty
// image or bad parameters (extract_silhouette checks first).
cv::Mat binarise(const cv::Mat& image, const BinariseParams& p);

// Describes a closed pixel contour (as cv::findContours gives it with CHAIN_APPROX_NONE): the
// chain's zigzag is smoothed out (sigma 1 px), the outline resampled every pixel of its arc length
// (exactly: length / round(length)), smoothed along the arc with a Gaussian of sigma scale_px
// pixels, and at every resampled point the smoothed curve's unit tangent, the normal out of the
// object and the signed curvature (1/pixel, convex positive) are taken; see fba::Outline for the
// conventions. `hole`: the contour bounds a hole (the object is outside it), so the normals point
// into it. The contour's direction does not matter. A contour of fewer than 3 points, or of no
// length, is returned as it is with zero tangents, normals and curvature. metric_curvature is left
// empty. Throws std::invalid_argument when scale_px <= 0.
// Accuracy: a binary mask knows the outline only to +-0.5 px, and on a curve of radius r that
// error comes in runs of up to sqrt(2 r) px, so the scale must be a fair share of r. On a disc of
// radius 150 px (every point; plugins/vision/tests) the curvature is within 0.55..1.28 of 1/r at
// scale 8, 0.92..1.04 at 16, 0.96..1.03 at 20 (the default), 0.98..1.03 at 24. Smoothing also
// shrinks a circle a little: its curvature comes out exp(scale^2 / (2 r^2)) / r (+0.9% for r = 150
// at 20 px; a hole's magnitude likewise).
fba::Outline describe_outline(const std::vector<cv::Point>& contour, bool hole, double scale_px);

// Index of the target among outer contours, by size and position; nullopt when none qualifies.
std::optional<std::size_t> select_target(const std::vector<std::vector<cv::Point>>& outer_contours,
                                         cv::Size image_size, const SelectionParams& p);

// The holes of `mask` (outer contours' children, at least min_hole_area_px) that do not look like
// the background in `grey` (see hole_background_tolerance) are filled.
void fill_holes_unlike_background(cv::Mat& mask, const cv::Mat& grey, const SelectionParams& p);

// Whole pipeline on one frame. The silhouette keeps a pointer to the frame. When the frame's
// camera has non-zero distortion the image is undistorted first and the silhouette's frame is
// the undistorted copy with zero distortion (the carver projects with an ideal pinhole).
ExtractionResult extract_silhouette(std::shared_ptr<const fba::Frame> frame, const ExtractionParams& p = {});

// The same, from a mask that is already binary (synthetic views, tests): selection and contour
// description only, no thresholding, clean-up or hole-against-background test.
ExtractionResult silhouette_from_mask(const cv::Mat& mask, std::shared_ptr<const fba::Frame> frame,
                                      const SelectionParams& p = {});

}  // namespace fba::vision
