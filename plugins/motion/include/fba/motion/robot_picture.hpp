// Pictures of a reach plan for people: the robot at the pregrasp (the hand open, where the straight
// approach starts) and at the top of the lift (the fingers closed on the object), rendered from the
// models the planner plans with: the arm's and the wrist camera's URDF collision shapes at the
// plan's joints, the hand's shapes (hand_parts()) at its opening, the table (z = 0), the carved
// model's occupied leaves above it (carried up with the hand at the lift) and the grasp's
// contacts. Both are seen from one fixed side view, so that they differ only where the robot and
// the object moved, and captioned (fba/vision/caption.hpp) with what each colour is.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "fba/motion/reach_planner.hpp"
#include "fba/types/camera.hpp"
#include "fba/types/grasp.hpp"
#include "fba/types/octree.hpp"

namespace fba::motion {

// The parts' colours (BGR), each shaded by the light: a surface facing away from it is as dark as
// 0.4 of its colour. The model as the model picture draws carved leaves; the contacts as every
// grasp picture marks them (thumb red, finger 1 green, finger 2 blue).
struct RobotPictureColours {
  static inline const cv::Vec3b arm{195, 150, 105};
  static inline const cv::Vec3b camera{70, 70, 70};
  static inline const cv::Vec3b hand{40, 130, 240};
  static inline const cv::Vec3b model{205, 205, 205};
  static inline const cv::Vec3b table{150, 185, 205};
  static inline const cv::Vec3b background{250, 248, 245};
};

enum class PlanPose {
  Pregrasp,  // the pregrasp joints, the hand open: the start of the straight approach
  Lift,      // the lift's joints, the fingers closed on the contacts: the top of the lift
};

// The camera both pictures of a plan are rendered with (`size`: the picture between its caption's
// bands): from the arm's side, a little in front of it and above, looking at and framing the arm's
// base, the model's leaves and the robot at both poses. Throws std::invalid_argument for a size
// under 64 x 64, or a plan that is not ok.
CameraModel robot_picture_camera(const ReachPlanner& planner, const ReachPlan& plan, const Octree& model,
                                 cv::Size size = {800, 600});

// The robot at `pose` of `plan` (planned by `planner` for `grasp` on `model`), rendered with
// `camera` and captioned: the title names `object` (empty: "the object"), the pose and its time
// on the plan's clock. The captioned picture's pixel (u, v + vision::kCaptionHeaderRows) is the
// camera's (u, v). Throws std::invalid_argument for a plan without its steps (reachable()'s) or a
// URDF mesh shape (the planner refuses those too).
cv::Mat robot_picture(const ReachPlanner& planner, const ReachPlan& plan, const Grasp& grasp, const Octree& model, PlanPose pose,
                      const CameraModel& camera, const std::string& object = {});

// Both pictures, with robot_picture_camera's view, written into `dir` as robot_pregrasp.png and
// robot_lift.png; returns their paths. Throws as robot_picture, and std::runtime_error naming a
// file that cannot be written.
std::vector<std::filesystem::path> write_robot_pictures(const std::filesystem::path& dir, const ReachPlanner& planner,
                                                        const ReachPlan& plan, const Grasp& grasp, const Octree& model,
                                                        const std::string& object = {});

}  // namespace fba::motion
