// The live views (fba/view.hpp) of the types that need only Eigen (Pose, JointState,
// JointTrajectory, Grasp, GraspCandidates, RegionsOfInterest, RobotDescription, Octree), registered
// when their library, libfba_robot_types, loads.
//
// Each of those types' headers includes this one, so that whatever uses the type loads the library
// that shows it: the reference below keeps the library among a plugin's needed libraries, which the
// linker's --as-needed (Debian's default) would otherwise drop, the types being header-only.
#pragma once

namespace fba::types_detail {
[[gnu::visibility("default")]] extern const bool robot_types_views_registered;
[[gnu::used]] inline const bool* const keep_robot_types_views = &robot_types_views_registered;
}  // namespace fba::types_detail
