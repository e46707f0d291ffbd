// The octree carver run once over a set of views: the model the tests compare with
// reference_carve's (same arguments) or look at on its own.
#pragma once

#include <memory>
#include <vector>

#include "fba/vision/octree_carver.hpp"

namespace fba::vision::test {

inline std::shared_ptr<const fba::Octree> fast_carve(const std::vector<fba::Silhouette>& views, const Eigen::AlignedBox3d& box,
                                                     const CarverParams& p, const fba::RegionsOfInterest& roi = {}) {
  OctreeCarver c(p);
  c.set_regions_of_interest(roi);
  c.set_bounds(box);
  c.add_views(views);
  return c.snapshot();
}

}  // namespace fba::vision::test
