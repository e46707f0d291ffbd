// The target's outline in one image.
#pragma once

#include <memory>
#include <vector>

#include <opencv2/core.hpp>

#include "fba/data_type.hpp"
#include "fba/types/frame.hpp"

namespace fba {

struct Silhouette {
  cv::Mat mask;                       // 8-bit, 255 inside the object, 0 outside; image size
  std::vector<cv::Point> contour;     // outer contour of the selected target, image pixels
  std::vector<double> curvature;      // signed curvature per contour point (1/pixel)
  std::shared_ptr<const Frame> frame; // the frame it was extracted from (camera, pose, image)
  bool touches_border = false;        // the target leaves the image on this view
};

}  // namespace fba

FBA_DATA_TYPE(fba::Silhouette, "fba.Silhouette",
              "A target mask with its contour, per-point curvature, and the source frame.");
