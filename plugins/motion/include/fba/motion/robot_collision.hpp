// Collision checking of the arm, its wrist camera and the hand on its flange (FCL), at given joint
// positions, against the table (the half-space below z = 0), the arm itself (links not joined by
// a joint) and the carved model (ModelObstacles). Shapes from the URDF's <collision> elements and
// from hand_parts().
#pragma once

#include <memory>
#include <span>
#include <string>

#include <Eigen/Geometry>

#include "arm_model.hpp"
#include "fba/motion/model_obstacles.hpp"

namespace fba::motion {

// Where the palm sits on the flange, as the robot's URDF (its text, `origin` naming it in messages:
// arm::RobotDescription) places it (the fixed joint between them), so that every reader of the one
// description puts the hand at the same place. Throws arm::ArmModelError when either link is not
// on a chain from `base_link`.
Eigen::Isometry3d urdf_flange_from_palm(const std::string& urdf_xml, const std::string& origin, const std::string& base_link,
                                        const std::string& flange_link = "flange", const std::string& palm_link = "palm");

class RobotCollision {
 public:
  // `arm`: a chain from the world to the flange; the palm sits at flange_from_palm on its last
  // link. The hand starts open, at the scissor's narrowest. Throws std::invalid_argument for a
  // URDF mesh shape (only boxes, cylinders and spheres are checked).
  RobotCollision(const arm::ArmModel& arm, const Eigen::Isometry3d& flange_from_palm);
  ~RobotCollision();
  RobotCollision(RobotCollision&&) noexcept;
  RobotCollision& operator=(RobotCollision&&) noexcept;

  // The fingers at this opening and spread (hand_parts()).
  void set_hand(double opening, double spread);
  // The model to check against (null: none). The fingers may touch its boxes that come within
  // `radius` of one of `contacts`: there they are about to touch the object.
  void set_model(std::shared_ptr<const ModelObstacles> model, std::span<const Eigen::Vector3d> contacts = {},
                 double radius = 0);
  // Whether the model is checked: once the fingers have closed, the object moves with the hand.
  void check_model(bool on);
  // The model's boxes the arm's links and camera touch at `joints` are no obstacle from now on:
  // the arm stands there, so nothing of the object does (a corner of the workspace no view
  // carved, which the upper arm passes through). The hand's too with `with_hand`, at the opening
  // set_hand gave: left out by default, where its opening at `joints` is not the one to check.
  void free_model_at(const Eigen::VectorXd& joints, bool with_hand = false);

  // "" when the robot at `joints` touches nothing; else the first contact found, as
  // "<part> touches <what>": "upper_arm_link touches the table", "thumb touches the model at
  // (0.031, 0.000, 0.072)", "palm touches forearm_link".
  std::string collision(const Eigen::VectorXd& joints);
  // The same for the hand alone with the palm at world_from_palm (no arm): the table and the model.
  std::string hand_collision(const Eigen::Isometry3d& world_from_palm);
  // Whether the last collision() or hand_collision() that found a contact found it with the model
  // (space the views carved or have not carved yet), rather than the table or the arm itself.
  bool model_hit() const;

  const arm::ArmModel& arm() const;
  const Eigen::Isometry3d& flange_from_palm() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace fba::motion
