// Registers the shared types by name when the library loads, so fba-inspect and the task
// checker know them even before a component that produces them is created.
#include "fba/types/frame.hpp"
#include "fba/types/grasp.hpp"
#include "fba/types/mesh.hpp"
#include "fba/types/octree.hpp"
#include "fba/types/pose.hpp"
#include "fba/types/regions_of_interest.hpp"
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
  return true;
}();
}  // namespace
