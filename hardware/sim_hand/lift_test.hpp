// The lift test: a three-fingered hand executes a grasp on an object in the MuJoCo physics engine,
// the field's ground truth for "the grasp works". Once the object has settled on the table, the
// hand (hardware/robots/three_finger_hand.xml) goes to the pregrasp back along the approach (an
// opening whose way in is clear of the settled object), moves in, closes its fingers under force
// control until they stop on the object, lifts it and holds it; the outcome is measured in the
// physics.
// Simulated time alone decides (the step count), never the wall clock.
#pragma once

#include <cstddef>
#include <memory>
#include <stdexcept>
#include <string>

#include "fba/types/grasp.hpp"
#include "fba/types/grasp_execution.hpp"
#include "fba/types/mesh.hpp"
#include "object_placement.hpp"

namespace fba::sim_hand {

// A scene that cannot be built: a mesh that does not load, or a model MuJoCo does not compile
// (with MuJoCo's own message).
class LiftTestError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct LiftTestParams {
  double mass = 0.3;          // kg, spread over the mesh's volume
  double friction = 0.5;      // sliding friction of the object, the table and the fingers
  double lift_height = 0.1;   // metres, straight up
  double lift_s = 1.0;        // seconds the lift takes
  double hold_s = 2.0;        // seconds held after the lift
  double finger_force = 10;   // newtons at each finger's pad; the thumb pushes twice as hard
  double pregrasp_distance = 0.05;  // metres back along the approach where the hand starts
  double clearance = 0.01;    // metres between each pad and its contact at the pregrasp, at least
  // The object is out of the hand once it moved this far relative to the palm since closing.
  double drop_distance = 0.03;
  // Each finger must touch the object within this distance of its planned contact, measured
  // across the approach (where along the finger it touches does not count); else the hand took
  // another grasp than the one planned, and the test fails without lifting.
  double contact_tolerance = 0.025;
};

// The most triangles MuJoCo is given: a finer object is decimated to this for the physics by
// vertex clustering (geometry::decimate), whose grid is then a small share of a hand-sized object;
// its convex hull, which MuJoCo collides with, moves by less than a cube of the grid. MuJoCo's
// compile time grows faster than the triangle count, and its STL reader takes at most 200,000.
// object() keeps every triangle.
inline constexpr std::size_t kPhysicsTriangles = 50000;

// `mesh` is in the mesh file's frame; see ObjectPlacement. The hand model is the one in
// hardware/robots (built in); `hand_mjcf`, when given, replaces it (MJCF text with the same
// body, joint and actuator names). Throws LiftTestError.
class LiftTest {
 public:
  LiftTest(const TriangleMesh& mesh, const ObjectPlacement& placement, const LiftTestParams& params = {},
           const std::string& hand_mjcf = {});
  ~LiftTest();
  LiftTest(const LiftTest&) = delete;
  LiftTest& operator=(const LiftTest&) = delete;

  // Runs one lift test from the initial scene (each run starts afresh). The pregrasp opening is
  // the grasp's aperture, or wider where the way in along the approach would otherwise collide. A
  // grasp the hand cannot take (out of its reach, no collision-free way in, a finger that misses
  // its planned contact) gives held = false with the reason.
  // Throws std::invalid_argument for a grasp with non-finite values or a zero approach.
  GraspExecution run(const Grasp& grasp);

  // The safe state, from any thread: a run in progress opens the hand and ends (held = false, the
  // reason says so), and later runs end at once the same way.
  void stop();

  // The object as placed, world frame: for computing contacts on it.
  const TriangleMesh& object() const;
  // What MuJoCo was given instead of the object's mesh, with the triangle counts: empty when it
  // was given the mesh as it is (kPhysicsTriangles).
  const std::string& physics_note() const;
  // Simulated seconds and physics steps of the last run.
  double simulated_s() const;
  long steps() const;

  // The built-in hand model (MJCF text).
  static const std::string& hand_model();

 private:
  struct Impl;
  GraspExecution run_steps(const Grasp& grasp);
  std::unique_ptr<Impl> impl_;
};

}  // namespace fba::sim_hand
