#include "fba/types/pose_json.hpp"

namespace fba {

nlohmann::json pose_json(const Eigen::Isometry3d& world_from_frame) {
  const Eigen::Quaterniond q(world_from_frame.linear());
  const Eigen::Vector3d p = world_from_frame.translation();
  return {{"position", {p.x(), p.y(), p.z()}}, {"quaternion_wxyz", {q.w(), q.x(), q.y(), q.z()}}};
}

}  // namespace fba
