// libfba_robot_types: registers the views of the types that need only Eigen when the library loads
// (robot_types_views.hpp says why every such type's header refers to this flag).
#include "fba/types/robot_types_views.hpp"

#include "fba/types/grasp.hpp"
#include "fba/types/joint_state.hpp"
#include "fba/types/joint_trajectory.hpp"
#include "fba/types/octree.hpp"
#include "fba/types/pose.hpp"
#include "fba/types/regions_of_interest.hpp"
#include "fba/types/robot_description.hpp"
#include "fba/view.hpp"
#include "views.hpp"

namespace fba::types_detail {

const bool robot_types_views_registered = [] {
  using namespace fba::views;
  // By the types' own names (type_of), so a renamed type keeps its view.
  // Every pose is shown, in order: the camera's are the views visited.
  register_view(type_of<Pose>()->name, &pose_view, ViewedSamples::Every);
  register_view(type_of<JointState>()->name, &joint_state_view);
  register_view(type_of<JointTrajectory>()->name, &trajectory_view);
  register_view(type_of<Grasp>()->name, &grasp_view);
  register_view(type_of<GraspCandidates>()->name, &grasp_candidates_view);
  register_view(type_of<RegionsOfInterest>()->name, &regions_view);
  register_view(type_of<RobotDescription>()->name, &robot_view);
  register_view(type_of<Octree>()->name, &model_view);
  return true;
}();

}  // namespace fba::types_detail
