// The pictures of a reach plan (fba/motion/robot_picture.hpp): written for a planned grasp, the
// robot drawn where its model projects, and the pregrasp and the lift told apart where the robot
// and the object moved.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <tuple>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "fba/geometry/viewpoints.hpp"
#include "fba/motion/hand_geometry.hpp"
#include "fba/motion/robot_picture.hpp"
#include "fba/vision/caption.hpp"
#include "support/pictures.hpp"
#include "support/reach_scenes.hpp"
#include "support/temp_dir.hpp"

using namespace fba::motion;
using namespace fba::motion::test;

namespace {

// The box before the arm, taken from above, planned from sim.arm's first pose.
struct Scene {
  fba::Octree model = box_model(kBox);
  fba::Grasp grasp = box_grasp(kBox, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitZ(), 0.07);
  ReachPlan plan = planner().plan(grasp, model, home());
};

const Scene& scene() {
  static const Scene s;
  return s;
}

// Whether a pixel shows a part of this colour: the colour scaled by its shade (0.4 to 1, within
// rounding), which no other part's colour is.
bool shows(const cv::Vec3b& px, const cv::Vec3b& colour) {
  const Eigen::Vector3d p(px[0], px[1], px[2]), c(colour[0], colour[1], colour[2]);
  const double k = p.dot(c) / c.squaredNorm();
  return k >= 0.35 && k <= 1.05 && (p - k * c).cwiseAbs().maxCoeff() <= 3.0;
}

// The part of a captioned picture the camera rendered (between the caption's bands).
cv::Mat body(const cv::Mat& captioned) {
  return captioned(cv::Rect(0, fba::vision::kCaptionHeaderRows, captioned.cols,
                            captioned.rows - fba::vision::kCaptionHeaderRows - fba::vision::kCaptionLegendRows));
}

// The pixels that show the colour, and their mean position.
struct Coverage {
  int count = 0;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
};
Coverage coverage(const cv::Mat& picture, const cv::Vec3b& colour, cv::Rect within = {}) {
  if (within.area() == 0) within = cv::Rect(0, 0, picture.cols, picture.rows);
  within &= cv::Rect(0, 0, picture.cols, picture.rows);
  Coverage c;
  for (int v = within.y; v < within.y + within.height; ++v)
    for (int u = within.x; u < within.x + within.width; ++u)
      if (shows(picture.at<cv::Vec3b>(v, u), colour)) {
        ++c.count;
        c.mean += Eigen::Vector2d(u, v);
      }
  if (c.count > 0) c.mean /= c.count;
  return c;
}

Eigen::Vector2d projected(const fba::CameraModel& camera, const Eigen::Vector3d& p) {
  Eigen::Vector2d px;
  EXPECT_TRUE(fba::geometry::project(camera, p, px)) << p.transpose();
  return px;
}

}  // namespace

TEST(RobotPicture, BothPicturesOfAPlannedGraspAreWrittenCaptionedAndShowTheArmTheHandAndTheModel) {
  const Scene& s = scene();
  ASSERT_TRUE(s.plan.ok) << s.plan.why;
  const fba::test::TempDir dir;
  const auto files = write_robot_pictures(dir.path(), planner(), s.plan, s.grasp, s.model, "box");
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(files[0], dir.path() / "robot_pregrasp.png");
  EXPECT_EQ(files[1], dir.path() / "robot_lift.png");
  for (const auto& file : files) {
    const cv::Mat picture = cv::imread(file.string());
    ASSERT_FALSE(picture.empty()) << file;
    EXPECT_EQ(picture.size(), fba::vision::captioned_size({800, 600})) << file;
    EXPECT_GT(fba::test::legend_ink(picture), 0.02) << file;
    const cv::Mat b = body(picture);
    const double pixels = double(b.total());
    // The arm spans the picture (its base and its reach are framed); hand and object are smaller.
    EXPECT_GT(coverage(b, RobotPictureColours::arm).count / pixels, 0.03) << file;
    EXPECT_GT(coverage(b, RobotPictureColours::hand).count / pixels, 0.005) << file;
    EXPECT_GT(coverage(b, RobotPictureColours::model).count / pixels, 0.002) << file;
    EXPECT_GT(coverage(b, RobotPictureColours::table).count / pixels, 0.2) << file;
  }
}

TEST(RobotPicture, TheRobotIsDrawnWhereItsFlangeProjectsAndMovesBetweenThePregraspAndTheLift) {
  const Scene& s = scene();
  ASSERT_TRUE(s.plan.ok) << s.plan.why;
  const fba::CameraModel camera = robot_picture_camera(planner(), s.plan, s.model);
  const cv::Mat pregrasp = body(robot_picture(planner(), s.plan, s.grasp, s.model, PlanPose::Pregrasp, camera));
  const cv::Mat lift = body(robot_picture(planner(), s.plan, s.grasp, s.model, PlanPose::Lift, camera));
  ASSERT_EQ(pregrasp.size(), cv::Size(camera.width, camera.height));

  // Where the model puts the robot's last parts, projected: the arm's last shape (wrist_3_link's,
  // where the flange is) and the palm's centre (hand_parts()'s box) show the arm's and the hand's
  // colours (the palm's under the wrist camera's). (The flange itself lies in the gap the URDF's shapes leave between that link and the
  // palm: nothing of the robot's model is drawn there.)
  const auto& arm = planner().arm();
  const auto last = std::find_if(arm.collision_shapes().begin(), arm.collision_shapes().end(),
                                 [](const fba::arm::CollisionShape& c) { return c.link == "wrist_3_link"; });
  ASSERT_NE(last, arm.collision_shapes().end());
  const Eigen::Isometry3d palm_from_box(Eigen::Translation3d(0, 0, hand::kPalmCentreZ));
  for (const auto& [picture, q, name] :
       {std::tuple{&pregrasp, s.plan.pregrasp_joints, "pregrasp"}, std::tuple{&lift, s.plan.lift_joints, "lift"}}) {
    const Eigen::Vector3d wrist = (arm.link_poses(q).at(last->frame) * last->frame_from_shape).translation();
    const Eigen::Vector3d palm = (arm.forward(q) * planner().params().flange_from_palm * palm_from_box).translation();
    const auto around = [&](const Eigen::Vector3d& p) {
      const Eigen::Vector2d px = projected(camera, p);
      return cv::Rect(int(px.x()) - 5, int(px.y()) - 5, 11, 11);
    };
    EXPECT_GT(coverage(*picture, RobotPictureColours::arm, around(wrist)).count, 100) << name << ": the wrist";
    // The wrist camera stands on the palm, over its centre as seen from above.
    EXPECT_GT(coverage(*picture, RobotPictureColours::hand, around(palm)).count +
                  coverage(*picture, RobotPictureColours::camera, around(palm)).count,
              100)
        << name << ": the palm";
    EXPECT_EQ(coverage(*picture, RobotPictureColours::hand, around(wrist)).count, 0) << name << ": the wrist";
  }

  // The hand moved up by the standoff and the lift (5 + 10 cm, the grasp from above): its pixels
  // moved as its palm's projection did, and the pictures differ there.
  const Coverage hand_before = coverage(pregrasp, RobotPictureColours::hand), hand_after = coverage(lift, RobotPictureColours::hand);
  ASSERT_GT(hand_before.count, 0);
  ASSERT_GT(hand_after.count, 0);
  const Eigen::Vector2d palm_moved =
      projected(camera, s.plan.lift_palm.translation()) - projected(camera, s.plan.pregrasp_palm.translation());
  ASSERT_GT(palm_moved.norm(), 20) << "the palm's move is seen";
  EXPECT_LT((hand_after.mean - hand_before.mean - palm_moved).norm(), 0.35 * palm_moved.norm())
      << "hand's pixels moved " << (hand_after.mean - hand_before.mean).transpose() << ", its palm " << palm_moved.transpose();
  cv::Mat differ;
  cv::absdiff(pregrasp, lift, differ);
  cv::cvtColor(differ, differ, cv::COLOR_BGR2GRAY);
  EXPECT_GT(cv::countNonZero(differ > 0) / double(differ.total()), 0.005);
  const Eigen::Vector2d palm_lifted = projected(camera, s.plan.lift_palm.translation());
  EXPECT_GT(cv::countNonZero(differ(cv::Rect(int(palm_lifted.x()) - 10, int(palm_lifted.y()) - 10, 21, 21)) > 0), 100);

  // The object is carried up with the hand: the model's pixels moved up as far as the lift.
  const Coverage model_before = coverage(pregrasp, RobotPictureColours::model), model_after = coverage(lift, RobotPictureColours::model);
  ASSERT_GT(model_before.count, 0);
  ASSERT_GT(model_after.count, 0);
  const Eigen::Vector2d lifted = projected(camera, s.plan.lift_palm.translation()) - projected(camera, s.plan.grasp_palm.translation());
  EXPECT_LT(model_after.mean.y() - model_before.mean.y(), 0.5 * lifted.y()) << "the model rose in the picture";
}

TEST(RobotPicture, APlanWithoutItsTimelineOrARefusedOneIsNotDrawn) {
  const Scene& s = scene();
  const ReachPlan quick = planner().reachable(s.grasp, s.model, home());
  ASSERT_TRUE(quick.ok) << quick.why;
  const fba::CameraModel camera = robot_picture_camera(planner(), quick, s.model);
  EXPECT_THROW(robot_picture(planner(), quick, s.grasp, s.model, PlanPose::Lift, camera), std::invalid_argument);
  ReachPlan refused = s.plan;
  refused.ok = false;
  EXPECT_THROW(robot_picture_camera(planner(), refused, s.model), std::invalid_argument);
  EXPECT_THROW(robot_picture_camera(planner(), s.plan, s.model, {32, 32}), std::invalid_argument);
}
