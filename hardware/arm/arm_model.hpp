// An arm's kinematics from its URDF (urdfdom + kdl_parser + Orocos KDL): forward kinematics, IK for
// a tip pose, limit checks and a joint-space motion within the velocity limits. Shared by sim.arm
// and the real arm's driver, so both refuse the same commands.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace fba::arm {

// A URDF that cannot be read or parsed, a link that does not exist, a chain without joints.
class ArmModelError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct JointLimits {
  double lower = 0.0;     // rad (m for a prismatic joint); -inf for a continuous joint
  double upper = 0.0;
  double velocity = 0.0;  // rad/s (m/s); the URDF's <limit velocity>
};

struct IkOptions {
  int attempts = 32;                   // the seed given, then random seeds within the limits
  double position_tolerance = 1e-4;    // m
  double orientation_tolerance = 1e-3; // rad
  std::uint64_t seed = 1;              // of the random seeds: the same answer on every run
  // When set, a solution must also pass it: it returns "" for joint positions it accepts, else
  // why not (a collision, say). The nearest accepted solution is returned.
  std::function<std::string(const Eigen::VectorXd&)> accept;
};

struct IkResult {
  bool ok = false;
  Eigen::VectorXd joints;             // the solution, or the best attempt when !ok
  double position_error = 0.0;        // m, of `joints`
  double orientation_error = 0.0;     // rad, of `joints`
  std::string why;                    // when !ok: what was wrong with the best attempt
  int attempts = 0;                   // solver starts made
};

// One <collision> shape of a link that moves with the chain: a link on it, or one fixed to such a
// link (the camera on the flange).
struct CollisionShape {
  enum class Kind { Box, Cylinder, Sphere, Mesh };
  std::string link;             // the URDF link it belongs to
  std::size_t frame = 0;        // index into ArmModel::link_names(): the chain link it moves with
  // Movable joints between the base and `link`: shapes with the same count move as one body, and
  // counts one apart are joined by one joint.
  std::size_t joints_before = 0;
  Eigen::Isometry3d frame_from_shape = Eigen::Isometry3d::Identity();
  Kind kind = Kind::Box;
  // Box: the edge lengths; cylinder (along z): radius, length, 0; sphere: radius, 0, 0.
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
  std::string mesh;             // Kind::Mesh: its file name, as the URDF gives it
};

class ArmModel {
 public:
  // Loads the chain from `base_link` to `tip_link` of the URDF file. Throws ArmModelError.
  ArmModel(const std::filesystem::path& urdf, const std::string& base_link, const std::string& tip_link);
  // The same from URDF text; `origin` names it in messages.
  static ArmModel from_string(const std::string& xml, const std::string& origin, const std::string& base_link,
                              const std::string& tip_link);
  ArmModel(ArmModel&&) noexcept;
  ArmModel& operator=(ArmModel&&) noexcept;
  ~ArmModel();

  const std::string& base_link() const;
  const std::string& tip_link() const;
  // The movable joints from base to tip, in chain order, with their limits.
  const std::vector<std::string>& joint_names() const;
  const std::vector<JointLimits>& limits() const;
  std::size_t size() const { return joint_names().size(); }

  // base_from_tip for the given joint positions (size() of them).
  Eigen::Isometry3d forward(const Eigen::VectorXd& joints) const;
  // Empty when every joint is within its limits; else the first one that is not, with its value
  // and range ("joint 'elbow_joint' at 3.5 rad is outside [-3.14159, 3.14159]").
  std::string limit_violation(const Eigen::VectorXd& joints) const;
  // Joint positions that put the tip at base_from_tip, within the limits and tolerances: the
  // valid solution nearest `seed` among the attempts (KDL's Levenberg-Marquardt solver from
  // `seed`, then from random seeds).
  IkResult inverse(const Eigen::Isometry3d& base_from_tip, const Eigen::VectorXd& seed, const IkOptions& options = {}) const;

  // The links of the chain after the base, from base to tip (each segment's child link).
  const std::vector<std::string>& link_names() const;
  // base_from_link for each of link_names() at the given joint positions, in one pass.
  std::vector<Eigen::Isometry3d> link_poses(const Eigen::VectorXd& joints) const;
  // The URDF's <collision> shapes of those links and of the links fixed to them. A link fixed to
  // them that carries movable joints of its own (the hand on the flange) is another mechanism,
  // whose parts move with its joints: neither its shapes nor those beyond it are the arm's.
  const std::vector<CollisionShape>& collision_shapes() const;

 private:
  struct Impl;
  explicit ArmModel(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// The URDF text with the origins of the named fixed joints replaced: where a real robot's parts
// were measured to be (the arm's base on the table, the hand and the camera on the flange), given
// by a task's profile, for every reader of the one description. Throws ArmModelError naming the
// joint when it is missing or not fixed (with the fixed joints there are), or the text is not XML.
std::string with_fixed_joint_origins(const std::string& urdf_xml, const std::map<std::string, Eigen::Isometry3d>& origins,
                                     const std::string& origin_name = "the URDF");

// [x, y, z] in metres and [roll, pitch, yaw] in radians (URDF's <origin rpy>: about the fixed x,
// then y, then z) as a transform; throws std::invalid_argument naming `what` unless 6 finite values.
Eigen::Isometry3d pose_from_xyz_rpy(const std::vector<double>& xyz_rpy, const std::string& what);

// A synchronised trapezoidal motion between two joint vectors: a straight line in joint space,
// every joint starting and stopping together, each within its velocity and acceleration limit.
// The slowest joint (relative to its limits) sets the duration.
class JointTrajectory {
 public:
  // `max_velocity` and `max_acceleration` per joint, > 0.
  JointTrajectory(Eigen::VectorXd start, Eigen::VectorXd goal, const Eigen::VectorXd& max_velocity,
                  const Eigen::VectorXd& max_acceleration);
  double duration() const { return duration_; }  // s
  const Eigen::VectorXd& start() const { return start_; }
  const Eigen::VectorXd& goal() const { return goal_; }
  // Positions and velocities at time t (s, clamped to [0, duration]).
  void sample(double t, Eigen::VectorXd& positions, Eigen::VectorXd& velocities) const;

 private:
  Eigen::VectorXd start_, goal_;
  double v_ = 0.0, a_ = 0.0;  // peak speed and acceleration of the path parameter s in [0, 1]
  double ramp_ = 0.0;         // s, accelerating (and again decelerating)
  double duration_ = 0.0;
};

// The distance between two orientations, rad.
double angle_between(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b);

}  // namespace fba::arm
