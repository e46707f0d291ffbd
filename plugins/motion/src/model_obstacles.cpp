#include "fba/motion/model_obstacles.hpp"

#include <cstdint>
#include <map>

#include <fcl/geometry/shape/box.h>

#include "model_obstacles_impl.hpp"

namespace fba::motion {

ModelObstacles::ModelObstacles(const Octree& model) : impl_(std::make_unique<Impl>()) {
  // Leaves of one depth share one shape.
  std::map<int, std::shared_ptr<fcl::Boxd>> shapes;
  std::vector<fcl::CollisionObjectd*> objects;
  model.for_each_occupied_leaf([&](const OctreeCell& c) {
    auto& shape = shapes[c.depth];
    if (!shape) shape = std::make_shared<fcl::Boxd>(2 * c.half_size, 2 * c.half_size, 2 * c.half_size);
    fcl::Transform3d at = fcl::Transform3d::Identity();
    at.translation() = c.centre;
    auto object = std::make_unique<fcl::CollisionObjectd>(shape, at);
    object->setUserData(reinterpret_cast<void*>(static_cast<std::uintptr_t>(impl_->boxes.size() + 1)));
    impl_->boxes.push_back(c.box());
    objects.push_back(object.get());
    impl_->objects.push_back(std::move(object));
  });
  impl_->tree.registerObjects(objects);
  impl_->tree.setup();
}

ModelObstacles::~ModelObstacles() = default;

std::size_t ModelObstacles::size() const { return impl_->boxes.size(); }
const Eigen::AlignedBox3d& ModelObstacles::box(std::size_t i) const { return impl_->boxes.at(i); }

}  // namespace fba::motion
