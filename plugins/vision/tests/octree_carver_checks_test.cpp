// vision.octree_carver refuses what cannot give a model of the object, with the reason, instead
// of ending with an empty model, the whole root box or a box in the wrong unit.
#include <gtest/gtest.h>

#include <memory>

#include <opencv2/imgproc.hpp>

#include <fba/testing.hpp>
#include <fba/types/frame.hpp>
#include <fba/types/octree.hpp>
#include <fba/types/regions_of_interest.hpp>
#include <fba/types/silhouette.hpp>

#include "support/built_plugins.hpp"
#include "support/build_paths.hpp"
#include "support/data_sets.hpp"
#include "support/events.hpp"

using fba::testing::ComponentHarness;

namespace {

using fba::test::built_plugins;
using fba::test::has_event;

using fba::test::kDinoPar;
// The providers' tight box of the dino, in metres.
const std::vector<double> kDinoBox{-0.061897, -0.018874, -0.057845, 0.010897, 0.068227, 0.015495};

// The first n calibrated dino frames, from vision.image_set.
std::vector<std::shared_ptr<const fba::Frame>> dino_frames(int n) {
  ComponentHarness views(built_plugins(), "vision.image_set", {{"file", kDinoPar}, {"limit", std::int64_t(n)}});
  views.run();
  std::vector<std::shared_ptr<const fba::Frame>> out;
  for (const auto& p : views.packets("frame")) out.push_back(std::make_shared<const fba::Frame>(p.get<fba::Frame>()));
  return out;
}

// The mask as contour extraction gives it: touches_border when the target reaches the image's edge.
fba::Silhouette silhouette(std::shared_ptr<const fba::Frame> frame, cv::Mat mask) {
  fba::Silhouette s;
  const int last_row = mask.rows - 1, last_col = mask.cols - 1;
  s.touches_border = cv::countNonZero(mask.row(0)) + cv::countNonZero(mask.row(last_row)) + cv::countNonZero(mask.col(0)) +
                         cv::countNonZero(mask.col(last_col)) > 0;
  s.mask = std::move(mask);
  s.frame = std::move(frame);
  return s;
}

// Feeds the silhouettes to a carver with the dino's box, closes its input and runs it to the end.
std::unique_ptr<ComponentHarness> carve(const std::vector<fba::Silhouette>& views, std::vector<double> bounds = kDinoBox) {
  auto h = std::make_unique<ComponentHarness>(built_plugins(), "vision.octree_carver",
                                              fba::testing::Params{{"bounds", bounds}, {"max_depth", 5}, {"occupancy_threshold", 0}});
  for (const auto& s : views) h->push<fba::Silhouette>("silhouette", s);
  h->close("silhouette");
  h->run();
  return h;
}

}  // namespace

TEST(OctreeCarverChecks, AFrameWithoutAPoseIsRefusedNamingTheFrameAndItsSource) {
  auto frame = std::make_shared<fba::Frame>(*dino_frames(1).at(0));
  frame->has_pose = false;
  frame->index = 7;
  frame->source = "usb-camera";
  const auto h = carve({silhouette(frame, cv::Mat(frame->image.rows, frame->image.cols, CV_8UC1, cv::Scalar(255)))});
  EXPECT_NE(h->failure().find("frame 7 from 'usb-camera' has no camera pose; the carver needs calibrated frames"), std::string::npos)
      << h->failure();
  EXPECT_EQ(h->failure().find("viewing cones"), std::string::npos) << h->failure();
}

TEST(OctreeCarverChecks, NoSilhouetteAtAllFailsSayingNoImageHadATarget) {
  const auto h = carve({});
  EXPECT_NE(h->failure().find("no silhouette arrived"), std::string::npos) << h->failure();
  EXPECT_TRUE(has_event(h->events(), "suspect_model"));
}

TEST(OctreeCarverChecks, OneViewFailsSayingTheModelIsItsViewingCone) {
  const auto frames = dino_frames(1);
  cv::Mat blob = cv::Mat::zeros(frames[0]->image.rows, frames[0]->image.cols, CV_8UC1);
  cv::circle(blob, {320, 240}, 100, cv::Scalar(255), cv::FILLED);
  const auto h = carve({silhouette(frames[0], blob)});
  EXPECT_NE(h->failure().find("only 1 view"), std::string::npos) << h->failure();
  EXPECT_TRUE(has_event(h->events(), "suspect_model"));
}

// White images: every silhouette is the whole image, nothing is carved.
TEST(OctreeCarverChecks, SilhouettesThatAreTheWholeImageFailAsTheWholeRootBox) {
  std::vector<fba::Silhouette> views;
  for (const auto& f : dino_frames(3)) views.push_back(silhouette(f, cv::Mat(f->image.rows, f->image.cols, CV_8UC1, cv::Scalar(255))));
  const auto h = carve(views);
  EXPECT_NE(h->failure().find("the model is the whole root box"), std::string::npos) << h->failure();
  EXPECT_TRUE(has_event(h->events(), "suspect_model"));
}

// The dino's box given in millimetres: 1000 times the viewing cones' box.
TEST(OctreeCarverChecks, BoundsOrdersOfMagnitudeOffTheViewingConesFailAskingForMetres) {
  std::vector<fba::Silhouette> views;
  for (const auto& f : dino_frames(4)) {
    cv::Mat m = cv::Mat::zeros(f->image.rows, f->image.cols, CV_8UC1);
    cv::circle(m, {320, 240}, 120, cv::Scalar(255), cv::FILLED);
    views.push_back(silhouette(f, m));
  }
  std::vector<double> mm;
  for (double v : kDinoBox) mm.push_back(1000 * v);
  const auto h = carve(views, mm);
  EXPECT_NE(h->failure().find("are the bounds in metres?"), std::string::npos) << h->failure();
  EXPECT_TRUE(has_event(h->events(), "suspect_model"));
  // The same views in the right box give a model.
  EXPECT_EQ(carve(views)->failure(), "");
}

// The grasp criterion from regions of interest (grasp synthesis's boxes), with the generic one
// off: detail to the deepest level goes inside the region and nowhere else.
TEST(OctreeCarverGraspCriterion, RegionsOfInterestGetTheDetailAndNothingElseDoes) {
  ComponentHarness h(built_plugins(), "vision.octree_carver",
                     {{"bounds", kDinoBox}, {"max_depth", 6}, {"occupancy_threshold", 1}, {"detail_after_views", 0}}, {"regions"});
  fba::RegionsOfInterest roi;
  const Eigen::AlignedBox3d region(Eigen::Vector3d(-0.06, -0.02, -0.06), Eigen::Vector3d(-0.025, 0.07, 0.016));
  roi.boxes.push_back(region);
  h.push<fba::RegionsOfInterest>("regions", roi);
  for (const auto& f : dino_frames(4)) {
    cv::Mat m = cv::Mat::zeros(f->image.rows, f->image.cols, CV_8UC1);
    cv::circle(m, {320, 240}, 120, cv::Scalar(255), cv::FILLED);
    h.push<fba::Silhouette>("silhouette", silhouette(f, m));
  }
  h.close("silhouette");
  h.close("regions");
  h.run();
  ASSERT_EQ(h.failure(), "");
  const auto models = h.values<fba::Octree>("octree");
  ASSERT_FALSE(models.empty());
  // A deepest leaf is the child of a node that meets the region: within a parent's edge of it.
  const fba::Octree& model = models.back();
  const double parent_edge = model.bounds.sizes().x() / 32;
  const Eigen::AlignedBox3d near(region.min().array() - parent_edge, region.max().array() + parent_edge);
  int deep_inside = 0, deep_outside = 0;
  model.for_each_leaf([&](const fba::OctreeCell& c) {
    if (c.depth == 6) ++(near.contains(c.box()) ? deep_inside : deep_outside);
  });
  EXPECT_GT(deep_inside, 0);
  EXPECT_EQ(deep_outside, 0);
}

namespace {

// The last event called `name`'s payload, or "".
std::string last_payload(const ComponentHarness& h, const std::string& name) {
  std::string p;
  for (const auto& e : h.events())
    if (e.name == name) p = e.payload;
  return p;
}

}  // namespace

// With compare_uniform, the comparison with uniform detail is in a `detail` event after every
// update, so that a run stopped by an event rule (hand.held), which never reaches the end of the
// stream, has it; the end's own equals the last update's. Detail goes into a region of interest
// only (as in the test above), so the model has fewer nodes than uniform detail.
TEST(OctreeCarverDetail, CompareUniformIsReportedAfterEveryUpdateNotOnlyAtTheEnd) {
  ComponentHarness h(built_plugins(), "vision.octree_carver",
                     {{"bounds", kDinoBox}, {"max_depth", 5}, {"occupancy_threshold", 1}, {"detail_after_views", 0},
                      {"compare_uniform", true}},
                     {"regions"});
  fba::RegionsOfInterest roi;
  roi.boxes.emplace_back(Eigen::Vector3d(-0.06, -0.02, -0.06), Eigen::Vector3d(-0.025, 0.07, 0.016));
  h.push<fba::RegionsOfInterest>("regions", roi);
  const auto frames = dino_frames(4);
  for (const auto& f : frames) {
    cv::Mat m = cv::Mat::zeros(f->image.rows, f->image.cols, CV_8UC1);
    cv::circle(m, {320, 240}, 120, cv::Scalar(255), cv::FILLED);
    h.push<fba::Silhouette>("silhouette", silhouette(f, m));
  }
  h.run();  // the inputs are still open: no end of stream
  ASSERT_EQ(h.failure(), "");
  std::size_t details = 0;
  for (const auto& e : h.events()) details += e.name == "detail";
  EXPECT_EQ(details, frames.size());
  const std::string running = last_payload(h, "detail");
  EXPECT_NE(running.find("\"uniform_nodes\": "), std::string::npos) << running;
  EXPECT_NE(running.find("\"saved_share\": 0."), std::string::npos) << running;
  EXPECT_EQ(running.find("\"saved_share\": 0.0000"), std::string::npos) << running;

  h.close("silhouette");
  h.close("regions");
  h.run();
  ASSERT_EQ(h.failure(), "");
  EXPECT_EQ(last_payload(h, "detail"), running);
}

// Without compare_uniform, `detail` stays an end-of-stream report.
TEST(OctreeCarverDetail, WithoutCompareUniformDetailComesOnceAtTheEnd) {
  ComponentHarness h(built_plugins(), "vision.octree_carver",
                     {{"bounds", kDinoBox}, {"max_depth", 4}, {"occupancy_threshold", 0}, {"detail_after_views", 0}});
  for (const auto& f : dino_frames(4)) {
    cv::Mat m = cv::Mat::zeros(f->image.rows, f->image.cols, CV_8UC1);
    cv::circle(m, {320, 240}, 120, cv::Scalar(255), cv::FILLED);
    h.push<fba::Silhouette>("silhouette", silhouette(f, m));
  }
  h.run();
  EXPECT_EQ(last_payload(h, "detail"), "");
  h.close("silhouette");
  h.run();
  ASSERT_EQ(h.failure(), "");
  EXPECT_NE(last_payload(h, "detail").find("\"model_nodes\": "), std::string::npos);
  EXPECT_EQ(last_payload(h, "detail").find("uniform_nodes"), std::string::npos);
}
