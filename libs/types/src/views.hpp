// The types' views (fba/view.hpp): the VIEW objects of docs/live-view.md, one function per type,
// registered by robot_types_views.cpp and image_views.cpp when their library loads. Each returns
// "" (show nothing) for a sample it cannot show, and never throws.
#pragma once

#include <cstddef>
#include <string>

#include "fba/packet.hpp"

namespace fba::views {

// Leaves a model's view holds at most; past it the model is shown at the deepest depth that fits
// (deeper leaves as their ancestor there), and says so ("truncated").
constexpr std::size_t kMaxModelLeaves = 40000;
// An image's view fits in this many pixels each way (downscaled, never enlarged).
constexpr int kMaxImageSide = 640;
// A trajectory's view holds at most this many waypoints (evenly spaced, the last kept).
constexpr std::size_t kMaxTrajectoryPoints = 1000;

std::string pose_view(const Packet& p);           // fba.Pose: "pose"
std::string joint_state_view(const Packet& p);    // fba.JointState: "joints"
std::string trajectory_view(const Packet& p);     // fba.JointTrajectory: "trajectory"
std::string grasp_view(const Packet& p);          // fba.Grasp: "grasps"
std::string grasp_candidates_view(const Packet& p);  // fba.GraspCandidates: "grasps"
std::string regions_view(const Packet& p);        // fba.RegionsOfInterest: "regions"
std::string robot_view(const Packet& p);          // fba.RobotDescription: "robot"
std::string model_view(const Packet& p);          // fba.Octree: "model"
std::string frame_view(const Packet& p);          // fba.Frame: "image", JPEG
std::string silhouette_view(const Packet& p);     // fba.Silhouette: "image", the mask as PNG, with its contours

}  // namespace fba::views
