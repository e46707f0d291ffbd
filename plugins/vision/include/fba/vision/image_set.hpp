// Calibrated image sets on disk: the Middlebury multi-view format, fba's own YAML format
// (docs/image-set-format.md), and OpenCV calibration files.
//
// Loading a set reads only the text files and each image's size; pixels are read on demand by
// load_frame(). Every malformed input throws FormatError naming the file, the line where one is
// known, what was expected and what was found; so does a view that disagrees with the set (an
// image of another size than the views sharing its camera, a focal length outside 0.001..1000
// times the image's larger side, a camera centre not finite or over 1000 times the set's spread
// away from the others).
#pragma once

#include <cstddef>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "fba/types/camera.hpp"
#include "fba/types/frame.hpp"

namespace fba::vision {

class FormatError : public std::runtime_error {
 public:
  // line 0: no line number is known (binary files, or an error about the whole file).
  FormatError(std::string file, int line, const std::string& what);
  const std::string& file() const { return file_; }
  int line() const { return line_; }

 private:
  std::string file_;
  int line_;
};

// One image of a set: where it is and the camera that took it.
struct ViewDescriptor {
  std::string name;    // as written in the set file (e.g. "dinoSR0001.png")
  std::string path;    // resolved path (relative names are taken relative to the set file)
  int index = 0;       // 1-based position in the set file (Middlebury numbering)
  CameraModel camera;  // width and height are those of the image file
  std::string mask_path;  // the provider's silhouette mask (YAML 'mask'), resolved; empty when none
};

class ImageSet {
 public:
  ImageSet() = default;
  explicit ImageSet(std::vector<ViewDescriptor> views) : views_(std::move(views)) {}

  // Middlebury "*_par.txt": a count line, then "name k11..k33 r11..r33 t1 t2 t3" per image,
  // P = K [R | t]. good_list: optional file of image names to keep (one per line, e.g.
  // "dinoSR_good_silhouette_images.txt"); empty keeps every image.
  static ImageSet load_middlebury(const std::string& par_file, const std::string& good_list = {});
  // fba's own YAML format, see docs/image-set-format.md.
  static ImageSet load_yaml(const std::string& file);
  // By name: "*_par.txt" is Middlebury (with the good-silhouette list beside it if present when
  // use_good_list), anything else fba YAML.
  static ImageSet load(const std::string& file, bool use_good_list = true);

  // Writes fba's YAML format; image paths are written relative to the file's directory.
  void save_yaml(const std::string& file) const;

  const std::vector<ViewDescriptor>& views() const { return views_; }
  std::size_t size() const { return views_.size(); }
  const ViewDescriptor& operator[](std::size_t i) const { return views_.at(i); }

  // Reads view i's pixels (BGR, or grey for grey files). Throws FormatError when the image is
  // missing or unreadable, or its size differs from the one recorded at load time.
  Frame load_frame(std::size_t i) const;

  // Whether every view has a provider's mask (a silhouette made independently of fba).
  bool has_masks() const;
  // View i's mask as CV_8U, 0 outside and 255 inside (any non-zero pixel is inside). Throws
  // FormatError when the view has none, or it is unreadable or of another size than the image.
  cv::Mat load_mask(std::size_t i) const;

  // For an exploration loop: the view not yet served whose camera is nearest the requested one.
  // Distance = centre distance (m) + angle_weight (m/rad) * angle between optical axes.
  // nullopt when every view has been served.
  std::optional<std::size_t> nearest_unserved_view(const Eigen::Isometry3d& requested_world_from_camera,
                                                   const std::set<std::size_t>& served,
                                                   double angle_weight = 0.1) const;
  // Position only (the camera centre in world coordinates).
  std::optional<std::size_t> nearest_unserved_view(const Eigen::Vector3d& requested_centre,
                                                   const std::set<std::size_t>& served) const;

 private:
  static ImageSet load_yaml_checked(const std::string& file);  // load_yaml once the file is known to be text

  std::vector<ViewDescriptor> views_;
};

// OpenCV's calibration file (YAML or XML, as written by the calibration sample): camera_matrix,
// distortion_coefficients, image_width, image_height. The pose is left at identity.
CameraModel load_opencv_calibration(const std::string& file);

// Width and height of an image file without decoding it when it is a PNG (header read), else by
// decoding it. Throws FormatError when unreadable.
cv::Size image_file_size(const std::string& path);

}  // namespace fba::vision
