// One captured image with everything needed to use it geometrically.
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "fba/data_type.hpp"
#include "fba/types/image_views.hpp"
#include "fba/types/camera.hpp"

namespace fba {

struct Frame {
  cv::Mat image;          // BGR 8-bit, or 8-bit grey
  CameraModel camera;     // intrinsics, distortion, and the camera's pose at capture time
  bool has_pose = false;  // false when no pose source was connected
  double stamp = 0.0;     // seconds
  std::string source;     // file name, device or "sim", for logs and artefacts
  int index = -1;         // view index within its source, -1 when not meaningful
};

}  // namespace fba

FBA_DATA_TYPE(fba::Frame, "fba.Frame",
              "An image with intrinsics, distortion, the camera pose at capture and a time stamp.");
