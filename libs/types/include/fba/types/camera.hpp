// A calibrated pinhole camera: intrinsics, lens distortion and pose.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

namespace fba {

struct CameraModel {
  int width = 0;
  int height = 0;
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  // OpenCV's distortion vector (k1 k2 p1 p2 [k3 ...]); empty for an ideal pinhole.
  cv::Mat distortion;
  // camera_from_world: x_cam = R * x_world + t, as in P = K [R | t].
  Eigen::Isometry3d camera_from_world = Eigen::Isometry3d::Identity();

  Eigen::Matrix<double, 3, 4> projection() const {
    return K * camera_from_world.matrix().topRows<3>();
  }
  Eigen::Vector3d centre_in_world() const { return camera_from_world.inverse().translation(); }
};

}  // namespace fba
