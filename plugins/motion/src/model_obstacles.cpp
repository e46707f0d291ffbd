#include "fba/motion/model_obstacles.hpp"

#include <algorithm>
#include <cstdint>
#include <map>

#include <fcl/geometry/shape/box.h>

#include "model_obstacles_impl.hpp"

namespace fba::motion {

namespace {

constexpr std::uint32_t kLeafBoxes = 4;

// Builds the node over order[first, last) at the end of `nodes`: the boxes split at the median of
// their centres along the longest side of the centres' bounds (a depth of log2(n / kLeafBoxes),
// well within visit()'s stack for any model an octree holds).
void build(ModelObstacles::Impl& m, std::uint32_t first, std::uint32_t last) {
  Eigen::AlignedBox3d bound, centres;
  for (std::uint32_t k = first; k < last; ++k) {
    bound.extend(m.boxes[m.order[k]]);
    centres.extend(m.boxes[m.order[k]].center());
  }
  const auto self = static_cast<std::uint32_t>(m.nodes.size());
  m.nodes.push_back({bound.center(), bound.diagonal().norm() / 2, first, 0, 0});
  if (last - first <= kLeafBoxes) {
    m.nodes[self].count = last - first;
    return;
  }
  int axis = 0;
  centres.diagonal().maxCoeff(&axis);
  const std::uint32_t middle = first + (last - first) / 2;
  std::nth_element(m.order.begin() + first, m.order.begin() + middle, m.order.begin() + last,
                   [&](std::uint32_t a, std::uint32_t b) { return m.boxes[a].center()(axis) < m.boxes[b].center()(axis); });
  build(m, first, middle);
  m.nodes[self].right = static_cast<std::uint32_t>(m.nodes.size());
  build(m, middle, last);
}

}  // namespace

ModelObstacles::ModelObstacles(const Octree& model) : impl_(std::make_unique<Impl>()) {
  // Leaves of one depth share one shape.
  std::map<int, std::shared_ptr<fcl::Boxd>> shapes;
  model.for_each_occupied_leaf([&](const OctreeCell& c) {
    auto& shape = shapes[c.depth];
    if (!shape) shape = std::make_shared<fcl::Boxd>(2 * c.half_size, 2 * c.half_size, 2 * c.half_size);
    fcl::Transform3d at = fcl::Transform3d::Identity();
    at.translation() = c.centre;
    auto object = std::make_unique<fcl::CollisionObjectd>(shape, at);
    object->computeAABB();
    impl_->boxes.push_back(c.box());
    impl_->objects.push_back(std::move(object));
  });
  impl_->order.resize(impl_->boxes.size());
  for (std::uint32_t i = 0; i < impl_->order.size(); ++i) impl_->order[i] = i;
  if (!impl_->boxes.empty()) build(*impl_, 0, static_cast<std::uint32_t>(impl_->boxes.size()));
}

ModelObstacles::~ModelObstacles() = default;

std::size_t ModelObstacles::size() const { return impl_->boxes.size(); }
const Eigen::AlignedBox3d& ModelObstacles::box(std::size_t i) const { return impl_->boxes.at(i); }

}  // namespace fba::motion
