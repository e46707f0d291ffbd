// The reference carve: the node test of octree_carver.hpp in the plainest form (every node,
// every view, the 8 corners projected, the bounding rectangle looked up in an integral image,
// one thread, level by level as in Algorithm 1). The correctness oracle and speed anchor for
// OctreeCarver.
#pragma once

#include <vector>

#include "fba/types/octree.hpp"
#include "fba/types/regions_of_interest.hpp"
#include "fba/types/silhouette.hpp"
#include "fba/vision/octree_carver.hpp"

namespace fba::vision {

// bounds is made a cube with geometry::cube_around(); params.threads is ignored.
fba::Octree reference_carve(const std::vector<fba::Silhouette>& views, const Eigen::AlignedBox3d& bounds,
                            const CarverParams& params, const fba::RegionsOfInterest& roi = {},
                            CarveStats* stats = nullptr);

}  // namespace fba::vision
