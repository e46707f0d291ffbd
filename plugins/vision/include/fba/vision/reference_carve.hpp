// The reference carve: the node test of octree_carver.hpp in the plainest form (every node, the
// views in order until one empties it, the 8 corners projected, the bounding rectangle looked up
// in a summed-area table, one thread, level by level as in Algorithm 1), written apart from the
// fast carver (it shares none of its code). The correctness oracle and speed anchor for
// OctreeCarver.
#pragma once

#include <vector>

#include "fba/types/octree.hpp"
#include "fba/types/regions_of_interest.hpp"
#include "fba/types/silhouette.hpp"
#include "fba/vision/octree_carver.hpp"

namespace fba::vision {

// bounds is made a cube with geometry::cube_around(); params.threads, parallel_for and
// memory_budget are ignored.
fba::Octree reference_carve(const std::vector<fba::Silhouette>& views, const Eigen::AlignedBox3d& bounds,
                            const CarverParams& params, const fba::RegionsOfInterest& roi = {},
                            CarveStats* stats = nullptr);

}  // namespace fba::vision
