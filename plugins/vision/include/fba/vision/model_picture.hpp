// Pictures of a carved model for people: the model from a viewpoint that shows the object, and the
// views taken around it, each captioned (caption.hpp) with what its colours mean.
//
// Each occupied leaf is drawn as what the model knows of it: carved (inside every silhouette that
// sees it, or on the outline at the finest depth), coarse (on the outline, not refined yet:
// synthesis does not trust a contact there), or not carved: seen by fewer than two views, so bounded
// by at most one cone of sight (nothing there was seen to be empty; the top of a root box no camera
// framed, for instance). That space is translucent and hatched, so that the object shows through
// it, and the picture frames the rest. The regions synthesis asked to refine are drawn as boxes.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "fba/types/camera.hpp"
#include "fba/types/grasp.hpp"
#include "fba/types/octree.hpp"

namespace fba::vision {

struct ModelPictureOptions {
  std::string object;                        // the object's name for the title; empty: "the object"
  std::vector<CameraModel> views;            // the views carved, in order; none: no leaf counts as unseen
  std::vector<Eigen::AlignedBox3d> regions;  // where synthesis asked for detail: drawn as boxes
  std::optional<double> table_z;             // the table under the object: leaves wholly below it are not drawn
  std::optional<Grasp> grasp;                // its contacts drawn (thumb red, fingers green and blue)
  cv::Size size{800, 600};                   // the rendered picture, before its caption's bands
};

// The whole model, seen three-quarters from above (beside the first view when there is one) at a
// distance that frames the drawn leaves, shaded, captioned. Throws std::invalid_argument for a
// picture size under 64 x 64.
cv::Mat model_picture(const Octree& model, const ModelPictureOptions& options);

// The model from farther out and higher, with each view's camera drawn where it stood, looking at
// the model, numbered in the order taken and joined in that order. Throws as model_picture.
cv::Mat views_picture(const Octree& model, const ModelPictureOptions& options);

// The object's name from a mesh or image-set path: data/ycb/YcbMustardBottle/model.obj gives
// "mustard bottle", sim_YcbMustardBottle (a simulated camera's frames) too, and a numbered image
// its folder's: middlebury-dino/dinoSR0001.png gives "middlebury dino". Empty: "the object".
std::string object_name(const std::string& path);

}  // namespace fba::vision
