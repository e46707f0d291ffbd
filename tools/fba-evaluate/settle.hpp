// How an object comes to rest on the table: dropped in MuJoCo from an orientation, stepped until it
// is still, its pose read. A stable pose, where the object lies as it would, rather than as its file
// stands or laid on its side (issue 31).
//
// The world: the table a plane at z = 0, gravity, a 2 ms step, elliptic friction cones, friction
// 0.5 with torsional and rolling friction (without rolling friction a ball or a lying cylinder
// never stops). The object collides as its convex parts (geometry::ConvexPart: MuJoCo's boxes,
// cylinders and ellipsoids, or a mesh's convex hull, which is how MuJoCo collides a mesh): for a
// lone object on a plane a hull is exact, its lowest points being on it. Its mass is the closed
// mesh's own (the lift test's 0.3 kg, the solid's centre of mass and inertia), not what MuJoCo
// would spread over the parts, which fill a ring's hole; the rest depends on it.
//
// Its turning is damped, with a time constant of a second: the dissipation of a real contact, which
// MuJoCo's soft contacts leave too small. Undamped, an ellipsoid close to a sphere rocked for a
// minute and a ring lying flat wobbled and spun on; damped, each of 20 ellipsoids (60 drops) came to
// rest within 0.1 degrees of the pole it is stable on. Damping holds no pose that gravity would not:
// it slows a motion, and a pose still for half a second is one that no torque turns.
//
// The model is handed to MuJoCo as the lift test hands its own, an MJCF text in a virtual file
// system, hulls' points written into it. Simulated time alone decides when it is still.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "fba/geometry/object_families.hpp"
#include "fba/types/mesh.hpp"

namespace fba::evaluate {

struct SettleParams {
  double drop_height = 0.02;   // m: the lowest point above the table when it is let go
  double mass = 0.3;           // kg
  double friction = 0.5;       // sliding; torsional 0.005 m, rolling 0.0001 m
  double timestep = 0.002;     // s
  double turn_damping_time = 1.0;  // s: a turn's decay time under the damping alone
  // Still: over each of the windows of the last still_time, its up direction (in its own frame)
  // turned less than still_tilt_deg and its origin moved less than still_move (m). Judged on the
  // pose, not the velocities: a body resting on MuJoCo's soft contacts keeps a jitter that goes
  // nowhere, and its turn about the vertical is no part of its rest. Looser, a superquadric rolling
  // slowly towards its pole was judged still 4 degrees off it; stricter, a tenth of the
  // superquadrics, resting on three of their hull's points at a time, were never still.
  double window = 0.25;
  double still_tilt_deg = 0.1;
  double still_move = 0.0002;
  double still_time = 1.0;
  double max_time = 60;        // s simulated: a drop still moving then is reported as not still
};

struct SettleResult {
  Eigen::Quaterniond dropped = Eigen::Quaterniond::Identity();  // the mesh's orientation when let go
  Eigen::Quaterniond settled = Eigen::Quaterniond::Identity();  // ... where it came to rest
  Eigen::Vector3d position = Eigen::Vector3d::Zero();          // where the mesh's origin came to rest, table frame
  bool still = false;   // still within max_time
  double time = 0;      // simulated seconds until judged still (max_time when not)
  long steps = 0;
  double lowest = 0;    // the mesh's lowest point at rest, m (below 0 by the soft contact's depth)
  std::vector<std::string> warnings;  // MuJoCo's, which would otherwise go to MUJOCO_LOG.TXT in the current folder
};

// An orientation drawn uniformly over all rotations (Shoemake's method) from mt19937_64's top 53
// bits: the same on any machine.
Eigen::Quaterniond random_orientation(std::uint64_t seed);

// `mesh` closed and outward, `parts` what collides (none: the mesh's hull), both in the mesh's
// frame; dropped in orientation `dropped` with the mesh's lowest point drop_height above the table,
// its origin over (0, 0). Throws std::invalid_argument for a mesh without volume, and
// std::runtime_error for a model MuJoCo refuses (with MuJoCo's message).
SettleResult settle(const TriangleMesh& mesh, const std::vector<geometry::ConvexPart>& parts, const Eigen::Quaterniond& dropped,
                    const SettleParams& params = {});

// The orientation's tilt alone: the rotation that takes the mesh's direction that is up in `q` to
// +z by the shortest way. `q` is this turned about the vertical, so it rests the same.
Eigen::Quaterniond tilt_only(const Eigen::Quaterniond& q);

}  // namespace fba::evaluate
