// sim.camera and sim.hand place the object alike: given the same placement parameters, the
// camera renders the object where the hand's lift test has it.
#include <gtest/gtest.h>

#include <string>

#include <opencv2/imgproc.hpp>

#include <fba/testing.hpp>
#include <fba/types/frame.hpp>
#include <fba/types/pose.hpp>

#include "fba/geometry/mesh_io.hpp"
#include "fba/geometry/viewpoints.hpp"
#include "object_placement.hpp"
#include "support/built_plugins.hpp"
#include "support/build_paths.hpp"
#include "support/data_sets.hpp"

namespace {

using fba::testing::ComponentHarness;

using fba::test::kCan;

// The object's box in the image sim.camera renders from above the table, and the box of the
// placed mesh's vertices projected with the same camera.
struct Boxes {
  cv::Rect rendered, projected;
};

Boxes boxes(double x, double y, double yaw_deg, const std::string& rest, double hand_yaw_deg) {
  ComponentHarness h(fba::test::built_plugins(), "sim.camera",
                     {{"mesh", kCan}, {"world", "table"}, {"object_x", x}, {"object_y", y}, {"object_yaw", yaw_deg},
                      {"object_rest", rest}},
                     {"pose"});
  fba::Pose above;
  above.world_from_frame = fba::geometry::look_at({0, 0, 0.6}, {0, 0, 0}, {0, 1, 0}).inverse();
  h.push<fba::Pose>("pose", above);
  h.run();
  const auto frames = h.packets("frame");
  EXPECT_EQ(frames.size(), 1u);
  if (frames.empty()) return {};
  const auto& f = frames[0].get<fba::Frame>();
  cv::Mat grey;
  cv::cvtColor(f.image, grey, cv::COLOR_BGR2GRAY);
  Boxes b;
  b.rendered = cv::boundingRect(grey > 60);
  fba::sim_hand::ObjectPlacement p{x, y, hand_yaw_deg * M_PI / 180, rest};
  const auto placed = fba::sim_hand::place_on_table(fba::geometry::load_mesh(kCan), p);
  std::vector<cv::Point2f> pixels;
  for (const auto& v : placed.vertices) {
    const Eigen::Vector3d q = f.camera.projection() * v.cast<double>().homogeneous();
    pixels.emplace_back(static_cast<float>(q.x() / q.z()), static_cast<float>(q.y() / q.z()));
  }
  b.projected = cv::boundingRect(pixels);
  return b;
}

void expect_near(const cv::Rect& a, const cv::Rect& b, int px) {
  EXPECT_NEAR(a.x, b.x, px);
  EXPECT_NEAR(a.y, b.y, px);
  EXPECT_NEAR(a.x + a.width, b.x + b.width, px);
  EXPECT_NEAR(a.y + a.height, b.y + b.height, px);
}

TEST(ObjectPlacement, TheCameraRendersTheObjectWhereTheHandHasIt) {
  for (const std::string rest : {"upright", "side"}) {
    SCOPED_TRACE(rest);
    const Boxes b = boxes(0.04, -0.03, 70, rest, 70);
    expect_near(b.rendered, b.projected, 3);
  }
  // A different turn is seen: the test tells placements apart (the can lying on its side is long).
  const Boxes turned = boxes(0.04, -0.03, 70, "side", 0);
  EXPECT_GT(std::abs(turned.rendered.width - turned.projected.width), 20);
}

}  // namespace
