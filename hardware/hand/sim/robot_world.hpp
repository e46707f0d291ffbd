// The MuJoCo world of the lift test, generated from the robot's one description: the URDF of the
// arm with its camera and its hand (hardware/robots/wrist_camera_arm.urdf), the table and the
// object as boxes.
//
// Generated here from urdfdom's model at run time rather than compiled by MuJoCo 2.2's own URDF
// reader: that reader fuses the fixed links into their parents (the flange, the palm, the camera
// and the pads would lose their bodies and names, whose poses are compared with KDL's), reads no
// actuators, and offers no place for the table and the object, which would then be spliced into
// MJCF that MuJoCo wrote back. Here every link is a body of its name at its joint's origin, every
// movable joint a joint with the URDF's limits and damping, driven by an actuator within its
// effort limit; the tuning URDF has no words for (rotor inertia, the phalanges' stiffness, contact
// classes) is chosen below by the joint's role, and no dimension is written here.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace fba::sim_hand {

// A description MuJoCo could not be given: a URDF that does not parse, a mesh shape, a joint type
// MuJoCo's tree has no counterpart for.
class RobotWorldError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct WorldObject {
  std::vector<Eigen::AlignedBox3d> boxes;  // world coordinates: the object's convex pieces (they may overlap)
  std::vector<Eigen::Vector3d> hull;       // world coordinates: when given, the robot touches these points' convex hull, not the boxes
  double mass = 0.3;                       // kg
  // The solid's centre of mass (world) and its inertia about it per unit mass (m^2); with a hull,
  // MuJoCo's from the hull.
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Identity() * 1e-4;
  double friction = 0.5;                   // sliding friction, of every geom of the world
};

// The world's MJCF: the table (the plane z = 0, the world frame), the robot from `urdf_xml` (its
// root link is the world), the object as a free body named "object" made of the boxes (geoms
// "object_N") and, for the table, their convex hull ("object_hull": a plane touches a solid only
// on its hull) with a small sphere at each corner of the footprint ("object_foot_N": a steady
// support on the base); given `hull`, the robot touches that hull ("object_shape") instead of the
// boxes.
// Contact classes: the robot's geoms touch the table and the object's boxes but not
// each other (the arm's self-collision is reach planning's to avoid); the arm's base, welded to
// the world, does not touch the table it is bolted to. Actuators: one per movable joint, named as it: a motor
// (N or N m, within the joint's effort limit) for the arm's joints and the fingers' closing
// slides, a position servo for the phalanges' springs and the scissor's slides.
std::string robot_world_mjcf(const std::string& urdf_xml, const std::string& origin_name, const WorldObject& object);

}  // namespace fba::sim_hand
