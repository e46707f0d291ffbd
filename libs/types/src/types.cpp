// Registers the shared types by name when the library loads, so fba-inspect and the task
// checker know them even before a component that produces them is created.
#include <algorithm>
#include <stdexcept>
#include <string>

#include "fba/types/frame.hpp"
#include "fba/types/grasp.hpp"
#include "fba/types/joint_state.hpp"
#include "fba/types/grasp_execution.hpp"
#include "fba/types/hand_command.hpp"
#include "fba/types/joint_trajectory.hpp"
#include "fba/types/mesh.hpp"
#include "fba/types/octree.hpp"
#include "fba/types/pose.hpp"
#include "fba/types/regions_of_interest.hpp"
#include "fba/types/robot_description.hpp"
#include "fba/types/silhouette.hpp"

namespace {
[[maybe_unused]] const bool registered = [] {
  fba::type_of<fba::Pose>();
  fba::type_of<fba::Frame>();
  fba::type_of<fba::Silhouette>();
  fba::type_of<fba::Octree>();
  fba::type_of<fba::RegionsOfInterest>();
  fba::type_of<fba::TriangleMesh>();
  fba::type_of<fba::Grasp>();
  fba::type_of<fba::GraspCandidates>();
  fba::type_of<fba::JointState>();
  fba::type_of<fba::GraspExecution>();
  fba::type_of<fba::JointTrajectory>();
  fba::type_of<fba::HandCommand>();
  fba::type_of<fba::RobotDescription>();
  return true;
}();
}  // namespace

namespace fba {

OctreeArena::OctreeArena(std::size_t max_blocks)
    : max_blocks_(std::min<std::size_t>(max_blocks, OctreeNode::kMaxBlocks)),
      chunks_(new std::atomic<OctreeBlock*>[(max_blocks_ >> kChunkBits) + 1]) {
  for (std::size_t i = 0; i <= (max_blocks_ >> kChunkBits); ++i) chunks_[i].store(nullptr, std::memory_order_relaxed);
}

OctreeArena::~OctreeArena() {
  for (std::size_t i = 0; i <= (max_blocks_ >> kChunkBits); ++i) delete[] chunks_[i].load(std::memory_order_relaxed);
}

std::uint32_t OctreeArena::allocate() {
  const std::uint32_t i = size_.fetch_add(1, std::memory_order_acq_rel);
  if (i >= max_blocks_) {
    size_.fetch_sub(1, std::memory_order_acq_rel);
    throw std::length_error("octree: more than " + std::to_string(max_blocks_) + " blocks of 8 nodes (" +
                            std::to_string(max_blocks_ * sizeof(OctreeBlock) >> 20) +
                            " MiB), the memory budget; lower the depth or raise the budget");
  }
  std::atomic<OctreeBlock*>& c = chunks_[i >> kChunkBits];
  if (!c.load(std::memory_order_acquire)) {
    std::lock_guard lock(grow_);
    if (!c.load(std::memory_order_relaxed)) c.store(new OctreeBlock[std::size_t(1) << kChunkBits], std::memory_order_release);
  }
  return i;
}

OctreeNode* Octree::split(OctreeNode& n, NodeState s) {
  if (!arena) arena = std::make_shared<OctreeArena>();
  const std::uint32_t b = arena->allocate();
  for (auto& c : (*arena)[b].child) c.set_state(s);
  n.set_children(b);
  node_count += 8;
  return (*arena)[b].child;
}

}  // namespace fba
