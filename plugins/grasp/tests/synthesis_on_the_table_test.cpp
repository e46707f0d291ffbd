// Grasp synthesis on objects lying on the table, carved by the real carver from rendered views in
// the grasp task's workspace at depth 6 (tasks/grasp.yaml): a low plate is taken from above with the
// robot's hand clear of the table, a sphere touching the table at a point is modelled and grasped,
// and every contact stands a margin inside its graspable region.
// The hand is checked as reach planning poses it (fba::motion's place_hand() and hand_parts()).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include <fba/testing.hpp>
#include <fba/types/grasp.hpp>
#include <fba/types/octree.hpp>

#include "fba/geometry/object_families.hpp"
#include "fba/geometry/viewpoints.hpp"
#include "fba/grasp/model_surface.hpp"
#include "fba/grasp/synthesis.hpp"
#include "fba/motion/hand_geometry.hpp"
#include "fba/motion/hand_placement.hpp"
#include "fba/motion/reach_planner.hpp"
#include "fba/vision/octree_carver.hpp"
#include "motion_hand.hpp"
#include "perfect_masks.hpp"
#include "support/built_plugins.hpp"

// A namespace of its own: the tests of this folder are compiled as one unity source.
namespace table_scene {

using fba::testing::ComponentHarness;

// The grasp task's workspace: a 26 cm cube on the table (z = 0).
const Eigen::AlignedBox3d kWorkspace(Eigen::Vector3d(-0.13, -0.13, -0.02), Eigen::Vector3d(0.13, 0.13, 0.24));

// `mesh` (centred on its bounding box) stood on the table at the workspace's centre.
fba::TriangleMesh standing(fba::TriangleMesh mesh) {
  Eigen::AlignedBox3f box;
  for (const auto& v : mesh.vertices) box.extend(v);
  const Eigen::Vector3f shift(-box.center().x(), -box.center().y(), -box.min().z());
  for (auto& v : mesh.vertices) v += shift;
  return mesh;
}

// Twelve views around the object at elevations min_deg..70 degrees, 0.3 m from a point 5 cm above
// the table, as the loop's views; perfect masks; carved at depth 6 in the workspace.
std::shared_ptr<const fba::Octree> carve(const fba::TriangleMesh& mesh, double min_deg) {
  return fba::test::carve_perfect_masks(
      mesh, kWorkspace, fba::geometry::hemisphere_views(12, min_deg * M_PI / 180, 70 * M_PI / 180, 0.3, Eigen::Vector3d(0, 0, 0.05)));
}

// The lowest point of the robot's hand over its poses for `g` (open at the pregrasp 5 cm back,
// open at the grasp, closed on the contacts), the palm placed as reach planning places it (stood
// back by the grasp's pinch depth); each part's lowest point worked out here on its own.
double lowest_hand_z(const fba::Grasp& g) {
  const fba::motion::HandPlacement place = fba::motion::place_hand(g, fba::motion::ReachParams{}.clearance);
  EXPECT_TRUE(place.why.empty()) << place.why;
  const Eigen::Vector3d a = place.world_from_palm.linear().col(2);
  const Eigen::Isometry3d& grasp_palm = place.world_from_palm;
  const Eigen::Isometry3d pregrasp_palm = Eigen::Translation3d(-a * fba::motion::ReachParams{}.standoff) * grasp_palm;
  double lowest = INFINITY;
  for (const auto& [palm, opening] : {std::pair{pregrasp_palm, place.opening}, std::pair{grasp_palm, place.opening}, std::pair{grasp_palm, place.width}})
    for (const auto& part : fba::motion::hand_parts(opening, place.spread)) {
      const Eigen::Isometry3d pose = palm * part.palm_from_part;
      if (part.kind == fba::motion::HandPart::Kind::Cylinder) {
        // The lowest of its two rims: a circle of the radius across the axis at each end.
        const Eigen::Vector3d half = pose.linear().col(2) * part.size.y() / 2;
        const double drop = part.size.x() * std::hypot(pose.linear()(2, 0), pose.linear()(2, 1));
        lowest = std::min({lowest, (pose.translation() + half).z() - drop, (pose.translation() - half).z() - drop});
        continue;
      }
      for (int corner = 0; corner < 8; ++corner) {
        const Eigen::Vector3d c(corner & 1 ? 1 : -1, corner & 2 ? 1 : -1, corner & 4 ? 1 : -1);
        lowest = std::min(lowest, (pose * c.cwiseProduct(part.size)).z());
      }
    }
  return lowest;
}

std::string events_text(const ComponentHarness& h) {
  std::string out;
  for (const auto& e : h.events()) out += e.name + ": " + e.payload + "\n";
  return out;
}

// grasp.synthesis as the grasp task has it on the table, the rims left out: these rules are the
// table's and the regions', not the views'.
std::vector<fba::Grasp> select(const fba::Octree& model, std::string& events) {
  ComponentHarness h(fba::test::built_plugins(), "grasp.synthesis", {{"max_views", 12}, {"table_z", std::vector<double>{0.0}}});
  h.push<fba::Octree>("octree", model);
  h.run();
  events = events_text(h);
  return h.values<fba::Grasp>("grasp");
}

std::string counts(const fba::grasp::SynthesisResult& r) {
  return std::to_string(r.regions.size()) + " regions; left out: " + std::to_string(r.near_edge) + " samples near an edge, " +
         std::to_string(r.too_low) + " too low; " + std::to_string(r.below_table) + " candidates into the table, " +
         std::to_string(r.hand_unfit) + " too wide, " + std::to_string(r.hand_blocked) + " blocked, " +
         std::to_string(r.not_force_closure) + " not force closure";
}

// Synthesis on the model's surface on the table, with the robot's hand and the grasp task's normal
// error (tasks/grasp.yaml), contacts at least `edge_margin` inside their regions.
fba::grasp::SynthesisResult synthesise(const fba::Octree& model, double edge_margin = 0.004) {
  fba::grasp::ModelSurfaceParams surface_params;
  surface_params.table_z = 0.0;
  const auto surface = fba::grasp::model_surface(model, surface_params);
  EXPECT_FALSE(surface.samples.empty());
  fba::grasp::SynthesisParams p;
  p.neighbour_radius = surface.radius;
  p.table_z = 0.0;
  p.robot_hand = fba::grasp::motion_hand(fba::motion::ReachParams{}.standoff, fba::motion::ReachParams{}.clearance);
  p.edge_margin = edge_margin;
  p.normal_error_deg = 7;
  return fba::grasp::synthesise(surface.samples, p);
}

}  // namespace table_scene

// A plate 2 cm tall: on its pads the hand would put its fingers 2.5 cm below the contacts, into the
// table, from any approach that opposes the plate's sides. It is taken from above as a pinch.
TEST(GraspSynthesisOnTheTable, AFlatPlateIsTakenFromAboveWithTheHandClearOfTheTable) {
  const auto r = table_scene::synthesise(*table_scene::carve(table_scene::standing(fba::geometry::make_box_shape(0.09, 0.07, 0.02)), 20));
  ASSERT_FALSE(r.candidates.empty()) << table_scene::counts(r);
  EXPECT_GT(r.too_low, 0u);       // samples no fingertip touches above the table, left out before the search
  EXPECT_GT(r.below_table, 0u);   // candidates whose hand reaches into it even as a pinch, left out after
  for (const auto& c : r.candidates) {
    const fba::Grasp& g = c.grasp;
    EXPECT_LT(g.approach.z(), -0.9) << g.approach.transpose();  // from above
    EXPECT_GT(g.pinch_depth, 0.0);
    EXPECT_GE(table_scene::lowest_hand_z(g), 0.0);
    fba::Grasp on_pads = g;
    on_pads.pinch_depth = 0;
    EXPECT_LT(table_scene::lowest_hand_z(on_pads), 0.0);  // what the pinch is for
  }
}

// A plate 1.3 cm tall: a fingertip rounded as the rest of the finger is (1 cm) would meet its sides
// no lower than 13 mm above the table, on its top edge. The flat fingertip pinches it, touching
// 3 mm short of its end, each contact on a side below that height.
TEST(GraspSynthesisOnTheTable, APlateLowerThanAFingertipsRadiusIsPinchedByTheFlatFingertips) {
  const auto r = table_scene::synthesise(*table_scene::carve(table_scene::standing(fba::geometry::make_box_shape(0.09, 0.07, 0.013)), 20));
  ASSERT_FALSE(r.candidates.empty()) << table_scene::counts(r);
  const double clearance = fba::grasp::SynthesisParams{}.table_clearance;
  const double rounded_tip_lowest = fba::motion::hand::kPadRadius + clearance;
  for (const auto& c : r.candidates) {
    const fba::Grasp& g = c.grasp;
    EXPECT_GT(g.pinch_depth, 0.0);
    EXPECT_GE(table_scene::lowest_hand_z(g), clearance - 1e-9);
    for (const auto& contact : g.contacts) {
      EXPECT_LT(contact.position.z(), rounded_tip_lowest);
      EXPECT_LT(std::abs(contact.normal.z()), 0.5) << "a contact on the plate's side, not its top";
    }
  }
}

// A sphere touches the table at one point: the leaves that straddle the table there have their
// centres under the sphere, and a view level with the table carves them, so the model's lowest leaf
// stands above the table. It is still the object, and grasped.
TEST(GraspSynthesisOnTheTable, ASphereRestingOnAPointIsModelledAndGrasped) {
  const auto model = table_scene::carve(table_scene::standing(fba::geometry::make_superquadric_shape(Eigen::Vector3d::Constant(0.03), 1, 1, 24)), 0);
  double lowest_leaf = INFINITY;
  model->for_each_occupied_leaf([&](const fba::OctreeCell& c) {
    if (c.centre.z() > 0.03) return;  // the sphere's lower half
    lowest_leaf = std::min(lowest_leaf, c.centre.z() - c.half_size);
  });
  ASSERT_GT(lowest_leaf, 0.0) << "the scene no longer carves the leaf under the sphere's contact";
  fba::grasp::ModelSurfaceParams params;
  params.table_z = 0.0;
  const auto surface = fba::grasp::model_surface(*model, params);
  ASSERT_FALSE(surface.samples.empty());
  double top = -INFINITY;
  for (const auto& s : surface.samples) top = std::max(top, s.position.z());
  EXPECT_GT(top, 0.055);  // the whole sphere, not a sliver

  std::string events;
  const auto grasps = table_scene::select(*model, events);
  ASSERT_EQ(grasps.size(), 1u) << events;
  EXPECT_GE(table_scene::lowest_hand_z(grasps[0]), 0.0);
  for (const auto& c : grasps[0].contacts) EXPECT_NEAR((c.position - Eigen::Vector3d(0, 0, 0.03)).norm(), 0.03, 0.006);
}

// A block on the table: every contact of every candidate stands at least the edge margin inside its
// graspable region, measured over the region; the samples nearer its edges are no contacts.
TEST(GraspSynthesisOnTheTable, EveryContactStandsTheEdgeMarginInsideItsRegion) {
  const double margin = 0.006;
  const auto r = table_scene::synthesise(*table_scene::carve(table_scene::standing(fba::geometry::make_box_shape(0.06, 0.08, 0.07)), 20), margin);
  ASSERT_FALSE(r.candidates.empty()) << table_scene::counts(r);
  EXPECT_GT(r.near_edge, 0u);
  for (const auto& c : r.candidates)
    for (std::size_t k = 0; k < 3; ++k) EXPECT_GE(r.boundary_distance[c.samples[k]], margin);
}
