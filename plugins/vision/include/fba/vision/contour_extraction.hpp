// The target's silhouette in one image: binarise, clean up, pick the target's contour, and
// describe it (filled mask, contour polygon, signed curvature, whether it leaves the image).
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
  // Holes at least this large (pixels) are kept as holes in the mask; smaller ones are filled.
  // Default: fill every hole, because shadows make false holes and a false hole carves away real
  // object, which conservative carving must never do.
  double min_hole_area_px = std::numeric_limits<double>::infinity();
  // Curvature scale in contour points (see contour_curvature).
  int curvature_window = 10;
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

// Signed curvature (1/pixel) at every point of a closed contour: positive where the outline is
// convex (bulges outwards), negative where concave, whatever the contour's orientation. The
// contour is first averaged over +-window/2 points, then the curvature is that of the circle
// through points i - window, i, i + window.
std::vector<double> contour_curvature(const std::vector<cv::Point>& contour, int window);

// Index of the target among outer contours, by size and position; nullopt when none qualifies.
std::optional<std::size_t> select_target(const std::vector<std::vector<cv::Point>>& outer_contours,
                                         cv::Size image_size, const SelectionParams& p);

// Whole pipeline on one frame. The silhouette keeps a pointer to the frame. When the frame's
// camera has non-zero distortion the image is undistorted first and the silhouette's frame is
// the undistorted copy with zero distortion (the carver projects with an ideal pinhole).
ExtractionResult extract_silhouette(std::shared_ptr<const fba::Frame> frame, const ExtractionParams& p = {});

// The same, from a mask that is already binary (synthetic views, tests): selection and contour
// description only, no thresholding or clean-up.
ExtractionResult silhouette_from_mask(const cv::Mat& mask, std::shared_ptr<const fba::Frame> frame,
                                      const SelectionParams& p = {});

}  // namespace fba::vision
