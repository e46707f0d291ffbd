// The grasp tests' carving from perfect masks (perfect_masks.hpp): a sphere seen from twelve views
// above it is kept whole, and space the views see beside it is carved away.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "fba/geometry/mesh_io.hpp"
#include "perfect_masks.hpp"

namespace {

bool in_a_leaf(const std::vector<Eigen::AlignedBox3d>& leaves, const Eigen::Vector3d& p) {
  for (const auto& b : leaves)
    if (b.contains(p)) return true;
  return false;
}

}  // namespace

TEST(PerfectMasks, ASphereIsKeptWholeAndTheSpaceBesideItCarved) {
  const double r = 0.04;
  const Eigen::AlignedBox3d bounds(Eigen::Vector3d::Constant(-0.06), Eigen::Vector3d::Constant(0.06));
  const double distance = fba::geometry::framing_distance(bounds, fba::test::kMaskWidth, fba::test::kMaskHeight, fba::test::kMaskFocal);
  const double deg = std::numbers::pi / 180;
  const auto model = fba::test::carve_perfect_masks(fba::geometry::make_uv_sphere(Eigen::Vector3d::Zero(), r, 128, 64), bounds,
                                                    fba::geometry::hemisphere_views(12, 10 * deg, 70 * deg, distance, Eigen::Vector3d::Zero()));
  ASSERT_TRUE(model);
  EXPECT_EQ(model->views, 12);
  const std::vector<Eigen::AlignedBox3d> leaves = fba::vision::occupied_leaves(*model);
  double volume = 0;
  for (const auto& b : leaves) volume += b.volume();
  EXPECT_GE(volume, 4.0 / 3.0 * std::numbers::pi * r * r * r);  // carving never removes the object
  // Points off the leaves' faces (a point on one may fall between two boxes by a rounding).
  const Eigen::Vector3d off(0.0013, 0.0021, 0.0007);
  for (const Eigen::Vector3d& p : {off, Eigen::Vector3d(off.x(), off.y(), 0.9 * r), Eigen::Vector3d(0.9 * r, off.y(), off.z())})
    EXPECT_TRUE(in_a_leaf(leaves, p)) << p.transpose();
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(0.055, 0.055, 0.055), Eigen::Vector3d(off.x(), off.y(), 0.055), Eigen::Vector3d(-0.055, off.y(), 0.03)})
    EXPECT_FALSE(in_a_leaf(leaves, p)) << p.transpose();
}
