// An octree model whose versions share their unchanged parts. A published Octree is immutable and
// safe to read from any thread while its producer goes on: the producer never writes a block that
// a published version can reach, it copies the path to what changed instead (copy on write), so
// publishing a version costs nothing and a new version costs what changed.
//
// Storage: a node is 8 bytes (state, flags and the index of its children's block in one word, and
// the occupancy); the 8 children of a node are one block of an append-only arena shared by the
// versions. A node's centre, size and depth follow from its path and are computed by the readers
// (for_each_node and friends), not stored.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <type_traits>

#include <Eigen/Geometry>

#include "fba/data_type.hpp"
#include "fba/types/robot_types_views.hpp"

namespace fba {

enum class NodeState : std::uint8_t {
  Empty,    // carved away: outside the object in some view
  Full,     // inside the object's silhouette in every view that sees it whole
  Partial,  // straddles the object's boundary (subdivided, or at the resolution limit)
};

// One stored node. Children are ordered by x (bit 0), then y (bit 1), then z (bit 2).
class OctreeNode {
 public:
  static constexpr int kFlagBits = 3;  // bits for the producer's own use (the carver's bookkeeping)
  static constexpr std::uint32_t kMaxBlocks = (std::uint32_t(1) << (32 - 3 - kFlagBits)) - 1;

  NodeState state() const { return static_cast<NodeState>(word_ & 3u); }
  float occupancy() const { return occupancy_; }  // lowest silhouette occupancy over the views that saw it
  float interest() const { return (word_ & 4u) ? 1.0f : 0.0f; }  // 1 when a grasp criterion drove its refinement
  bool is_leaf() const { return (word_ >> kChildShift) == 0; }
  std::uint32_t children() const { return (word_ >> kChildShift) - 1; }  // block index; not for a leaf
  bool flag(int i) const { return (word_ >> (3 + i)) & 1u; }

  void set_state(NodeState s) { word_ = (word_ & ~3u) | static_cast<std::uint32_t>(s); }
  void set_occupancy(float o) { occupancy_ = o; }
  void set_interest(bool on) { word_ = on ? (word_ | 4u) : (word_ & ~4u); }
  void set_children(std::uint32_t block) { word_ = (word_ & kLowMask) | ((block + 1) << kChildShift); }
  void clear_children() { word_ &= kLowMask; }
  void set_flag(int i, bool on) {
    const std::uint32_t b = std::uint32_t(1) << (3 + i);
    word_ = on ? (word_ | b) : (word_ & ~b);
  }

 private:
  static constexpr int kChildShift = 3 + kFlagBits;
  static constexpr std::uint32_t kLowMask = (std::uint32_t(1) << kChildShift) - 1;
  std::uint32_t word_ = static_cast<std::uint32_t>(NodeState::Partial);
  float occupancy_ = 0;
};
static_assert(sizeof(OctreeNode) == 8);

struct OctreeBlock {
  OctreeNode child[8];
};

// Append-only storage of blocks, shared by the versions of a tree. allocate() may run on several
// threads at once; blocks never move, so a pointer to one stays valid for the arena's life.
class OctreeArena {
 public:
  // Refuses (std::length_error, with the figures) to hold more than max_blocks blocks.
  explicit OctreeArena(std::size_t max_blocks = OctreeNode::kMaxBlocks);
  ~OctreeArena();
  OctreeArena(const OctreeArena&) = delete;
  OctreeArena& operator=(const OctreeArena&) = delete;

  std::uint32_t allocate();  // a new block of 8 default nodes (Partial leaves, occupancy 0)
  std::uint32_t size() const { return size_.load(std::memory_order_acquire); }
  std::size_t max_blocks() const { return max_blocks_; }
  OctreeBlock& operator[](std::uint32_t i) { return chunk(i)[i & kChunkMask]; }
  const OctreeBlock& operator[](std::uint32_t i) const { return chunk(i)[i & kChunkMask]; }

 private:
  static constexpr int kChunkBits = 12;  // 4096 blocks (256 KiB) per chunk
  static constexpr std::uint32_t kChunkMask = (std::uint32_t(1) << kChunkBits) - 1;
  OctreeBlock* chunk(std::uint32_t i) const { return chunks_[i >> kChunkBits].load(std::memory_order_acquire); }
  std::size_t max_blocks_;
  std::unique_ptr<std::atomic<OctreeBlock*>[]> chunks_;
  std::atomic<std::uint32_t> size_{0};
  std::mutex grow_;
};

// A node as the readers see it: its place, computed from the path, and its stored values.
struct OctreeCell {
  const OctreeNode* node = nullptr;
  int depth = 0;
  int x = 0, y = 0, z = 0;  // min corner on the lattice of its depth: 0 .. 2^depth - 1 per axis
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double half_size = 0;
  NodeState state() const { return node->state(); }
  float occupancy() const { return node->occupancy(); }
  float interest() const { return node->interest(); }
  bool is_leaf() const { return node->is_leaf(); }
  bool occupied() const { return node->state() != NodeState::Empty; }
  Eigen::AlignedBox3d box() const {
    const Eigen::Vector3d h = Eigen::Vector3d::Constant(half_size);
    return {centre - h, centre + h};
  }
};

struct Octree {
  Eigen::AlignedBox3d bounds;            // the root voxel (a cube), world coordinates
  int max_depth = 0;
  int views = 0;                         // views integrated so far
  OctreeNode root;
  std::shared_ptr<OctreeArena> arena;    // the children's blocks (shared with other versions); null: root only
  std::size_t node_count = 1;            // nodes reachable from the root; 0: no tree yet (no bounds)

  // The 8 children of n (a node of this tree), or nullptr for a leaf.
  const OctreeNode* children(const OctreeNode& n) const {
    return n.is_leaf() ? nullptr : (*arena)[n.children()].child;
  }
  std::size_t bytes() const { return node_count * sizeof(OctreeNode); }  // the model's nodes

  // Depth first, a node before its children. f(const OctreeCell&) returns void, or bool: false
  // skips the node's children.
  template <class F>
  void for_each_node(F&& f) const {
    if (node_count > 0) walk(root, 0, 0, 0, 0, f);
  }
  template <class F>
  void for_each_leaf(F&& f) const {
    for_each_node([&](const OctreeCell& c) {
      if (c.is_leaf()) f(c);
    });
  }
  // Leaves that are Full or Partial.
  template <class F>
  void for_each_occupied_leaf(F&& f) const {
    for_each_node([&](const OctreeCell& c) {
      if (c.is_leaf() && c.occupied()) f(c);
      return c.occupied();
    });
  }
  // The cell of node n at (depth, x, y, z).
  OctreeCell cell(int depth, int x, int y, int z, const OctreeNode& n) const {
    OctreeCell c;
    c.node = &n;
    c.depth = depth, c.x = x, c.y = y, c.z = z;
    const double edge = bounds.sizes().x() / double(std::int64_t(1) << depth);
    c.half_size = 0.5 * edge;
    c.centre = bounds.min() + edge * Eigen::Vector3d(x + 0.5, y + 0.5, z + 0.5);
    return c;
  }

  // For building a tree by hand (tests, converters) before it is shared: gives n (the root or a
  // node of this tree) 8 leaf children in state s and returns the first.
  OctreeNode* split(OctreeNode& n, NodeState s);

 private:
  template <class F>
  void walk(const OctreeNode& n, int depth, int x, int y, int z, F& f) const {
    const OctreeCell c = cell(depth, x, y, z, n);
    bool descend = true;
    if constexpr (std::is_same_v<decltype(f(c)), bool>) descend = f(c);
    else f(c);
    if (!descend || n.is_leaf()) return;
    const OctreeNode* k = children(n);
    for (int i = 0; i < 8; ++i)
      walk(k[i], depth + 1, 2 * x + (i & 1), 2 * y + ((i >> 1) & 1), 2 * z + ((i >> 2) & 1), f);
  }
};

}  // namespace fba

FBA_DATA_TYPE(fba::Octree, "fba.Octree",
              "An immutable octree model: nodes full / empty / partial with depth, bounds, occupancy and grasp interest.");
