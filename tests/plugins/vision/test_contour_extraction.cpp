#include <cmath>
#include <memory>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "fba/vision/contour_extraction.hpp"
#include "fba/vision/image_set.hpp"

using namespace fba::vision;

namespace {

const std::string kDino = std::string(FBA_SHARED_DATA_DIR) + "/middlebury-dino";

std::shared_ptr<const fba::Frame> frame_of(const cv::Mat& image) {
  auto f = std::make_shared<fba::Frame>();
  f->image = image;
  f->camera.width = image.cols;
  f->camera.height = image.rows;
  f->source = "synthetic";
  return f;
}

std::shared_ptr<const fba::Frame> dino_frame(const std::string& name) {
  const ImageSet set = ImageSet::load_middlebury(kDino + "/dinoSR_par.txt");
  for (std::size_t i = 0; i < set.size(); ++i)
    if (set[i].name == name) return std::make_shared<const fba::Frame>(set.load_frame(i));
  throw std::runtime_error("no view " + name);
}

// Mean curvature over contour points farther than `margin` from every point in `avoid`.
double mean_curvature_away_from(const fba::Silhouette& s, const std::vector<cv::Point2d>& avoid, double margin) {
  double sum = 0;
  int n = 0;
  for (std::size_t i = 0; i < s.contour.size(); ++i) {
    bool near = false;
    for (const auto& a : avoid) near = near || cv::norm(cv::Point2d(s.contour[i]) - a) < margin;
    if (!near) sum += s.curvature[i], ++n;
  }
  return n ? sum / n : NAN;
}

}  // namespace

TEST(BinariseRecipe, DinoViewOneAreaInSaneRangeAndLeavesTheTop) {
  // The README recipe (threshold 0.19, dilate 10, erode 7) is the default parameter set.
  const ExtractionParams p;
  EXPECT_DOUBLE_EQ(p.binarise.threshold, 0.19);
  EXPECT_EQ(p.binarise.dilate_px, 10);
  EXPECT_EQ(p.binarise.erode_px, 7);
  const ExtractionResult r = extract_silhouette(dino_frame("dinoSR0001.png"), p);
  ASSERT_TRUE(r.ok()) << r.error;
  const double fraction = cv::countNonZero(r.silhouette->mask) / (640.0 * 480.0);
  // The dino fills a large part of the frame, the black background the rest.
  EXPECT_GT(fraction, 0.25);
  EXPECT_LT(fraction, 0.60);
  EXPECT_TRUE(r.silhouette->touches_border);  // its back leaves the top of the image
  EXPECT_EQ(r.silhouette->curvature.size(), r.silhouette->contour.size());
  EXPECT_EQ(r.silhouette->frame->source.find("dinoSR0001.png") != std::string::npos, true);
  // The mask is one filled blob: the shadows did not cut holes into it.
  std::vector<std::vector<cv::Point>> cs;
  std::vector<cv::Vec4i> h;
  cv::findContours(r.silhouette->mask.clone(), cs, h, cv::RETR_CCOMP, cv::CHAIN_APPROX_SIMPLE);
  EXPECT_EQ(cs.size(), 1u);
}

TEST(BinariseRecipe, DinoViewFiveStaysInsideTheFrame) {
  const ExtractionResult r = extract_silhouette(dino_frame("dinoSR0005.png"));
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_FALSE(r.silhouette->touches_border);
  const double fraction = cv::countNonZero(r.silhouette->mask) / (640.0 * 480.0);
  EXPECT_GT(fraction, 0.15);
  EXPECT_LT(fraction, 0.50);
}

TEST(BinariseRecipe, ShadowGapsAreClosedByDilateThenErode) {
  // A bright object split by a dark 8 px "shadow" band: one blob after the recipe, two without.
  cv::Mat img(200, 200, CV_8UC1, cv::Scalar(5));
  cv::rectangle(img, cv::Rect(50, 50, 100, 100), cv::Scalar(200), cv::FILLED);
  cv::rectangle(img, cv::Rect(96, 50, 8, 100), cv::Scalar(30), cv::FILLED);
  std::vector<std::vector<cv::Point>> cs;
  cv::findContours(binarise(img, BinariseParams{}), cs, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
  EXPECT_EQ(cs.size(), 1u);
  BinariseParams raw;
  raw.dilate_px = raw.erode_px = 0;
  cv::findContours(binarise(img, raw), cs, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
  EXPECT_EQ(cs.size(), 2u);
}

TEST(BinariseRecipe, OtsuSeparatesTwoLevels) {
  cv::Mat img(100, 100, CV_8UC3, cv::Scalar(20, 20, 20));
  cv::circle(img, {50, 50}, 20, cv::Scalar(150, 150, 150), cv::FILLED);
  BinariseParams p;
  p.method = BinariseParams::Method::Otsu;
  p.dilate_px = p.erode_px = 0;
  const cv::Mat m = binarise(img, p);
  EXPECT_NEAR(cv::countNonZero(m), M_PI * 20 * 20, 60);
}

TEST(ContourExtraction, EmptyImageGivesAnErrorResultNotACrash) {
  const ExtractionResult r = extract_silhouette(frame_of(cv::Mat()));
  EXPECT_FALSE(r.ok());
  EXPECT_NE(r.error.find("empty image"), std::string::npos) << r.error;
  EXPECT_FALSE(extract_silhouette(nullptr).ok());
  const ExtractionResult black = extract_silhouette(frame_of(cv::Mat(100, 100, CV_8UC1, cv::Scalar(0))));
  EXPECT_FALSE(black.ok());
  EXPECT_NE(black.error.find("no contour"), std::string::npos) << black.error;
  const ExtractionResult floats = extract_silhouette(frame_of(cv::Mat(10, 10, CV_32FC1, cv::Scalar(1))));
  EXPECT_FALSE(floats.ok());
}

TEST(ContourExtraction, ObjectLeavingTheFrameIsFlagged) {
  cv::Mat img(200, 300, CV_8UC1, cv::Scalar(0));
  cv::circle(img, {280, 100}, 50, cv::Scalar(255), cv::FILLED);  // cut by the right edge
  ExtractionResult r = extract_silhouette(frame_of(img));
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_TRUE(r.silhouette->touches_border);
  img.setTo(0);
  cv::circle(img, {150, 100}, 50, cv::Scalar(255), cv::FILLED);
  r = extract_silhouette(frame_of(img));
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_FALSE(r.silhouette->touches_border);
}

TEST(ContourExtraction, SelectsBySizeAndNearestToThePoint) {
  cv::Mat img(200, 400, CV_8UC1, cv::Scalar(0));
  cv::circle(img, {80, 100}, 40, cv::Scalar(255), cv::FILLED);
  cv::circle(img, {300, 100}, 60, cv::Scalar(255), cv::FILLED);
  cv::circle(img, {200, 100}, 3, cv::Scalar(255), cv::FILLED);  // noise at the centre
  ExtractionParams p;
  p.binarise.dilate_px = p.binarise.erode_px = 0;
  p.selection.near_point = cv::Point2d(60, 90);
  ExtractionResult r = extract_silhouette(frame_of(img), p);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r.silhouette->mask.at<std::uint8_t>(100, 80), 255);
  EXPECT_EQ(r.silhouette->mask.at<std::uint8_t>(100, 300), 0);  // the other blob is not in the mask
  // Default point (image centre): the noise blob is too small, the nearer big disc wins.
  p.selection.near_point.reset();
  r = extract_silhouette(frame_of(img), p);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r.silhouette->mask.at<std::uint8_t>(100, 300), 255);
  EXPECT_EQ(r.silhouette->mask.at<std::uint8_t>(100, 200), 0);
}

TEST(ContourExtraction, SmallHolesFilledLargeHolesKeptOnRequest) {
  cv::Mat img(200, 200, CV_8UC1, cv::Scalar(0));
  cv::circle(img, {100, 100}, 80, cv::Scalar(255), cv::FILLED);
  cv::circle(img, {100, 100}, 30, cv::Scalar(0), cv::FILLED);  // a real hole (a handle)
  cv::circle(img, {150, 100}, 3, cv::Scalar(0), cv::FILLED);   // a speck of shadow
  ExtractionParams p;
  p.binarise.dilate_px = p.binarise.erode_px = 0;
  ExtractionResult r = extract_silhouette(frame_of(img), p);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r.silhouette->mask.at<std::uint8_t>(100, 100), 255);  // default: every hole filled
  p.selection.min_hole_area_px = 500;
  r = extract_silhouette(frame_of(img), p);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r.silhouette->mask.at<std::uint8_t>(100, 100), 0);    // the big hole is kept
  EXPECT_EQ(r.silhouette->mask.at<std::uint8_t>(100, 150), 255);  // the speck is filled
}

TEST(Curvature, DiscIsPositiveAboutOneOverRadius) {
  cv::Mat img(300, 300, CV_8UC1, cv::Scalar(0));
  cv::circle(img, {150, 150}, 60, cv::Scalar(255), cv::FILLED);
  ExtractionParams p;
  p.binarise.dilate_px = p.binarise.erode_px = 0;
  const ExtractionResult r = extract_silhouette(frame_of(img), p);
  ASSERT_TRUE(r.ok());
  const auto& k = r.silhouette->curvature;
  double mean = 0;
  for (double v : k) {
    EXPECT_GT(v, 0);
    mean += v;
  }
  mean /= static_cast<double>(k.size());
  EXPECT_NEAR(mean, 1.0 / 60, 0.2 / 60);
  // The sign does not depend on the contour's direction.
  std::vector<cv::Point> reversed(r.silhouette->contour.rbegin(), r.silhouette->contour.rend());
  for (double v : contour_curvature(reversed, p.selection.curvature_window)) EXPECT_GT(v, 0);
}

TEST(Curvature, SquareIsFlatOnSidesAndConvexAtCorners) {
  cv::Mat img(300, 300, CV_8UC1, cv::Scalar(0));
  cv::rectangle(img, cv::Rect(50, 50, 200, 200), cv::Scalar(255), cv::FILLED);
  ExtractionParams p;
  p.binarise.dilate_px = p.binarise.erode_px = 0;
  const ExtractionResult r = extract_silhouette(frame_of(img), p);
  ASSERT_TRUE(r.ok());
  const std::vector<cv::Point2d> corners{{50, 50}, {249, 50}, {249, 249}, {50, 249}};
  const auto& s = *r.silhouette;
  for (std::size_t i = 0; i < s.contour.size(); ++i) {
    double d = 1e9;
    for (const auto& c : corners) d = std::min(d, cv::norm(cv::Point2d(s.contour[i]) - c));
    if (d > 17) EXPECT_NEAR(s.curvature[i], 0.0, 1e-9) << s.contour[i];
    if (d < 1) EXPECT_GT(s.curvature[i], 0.05) << s.contour[i];
  }
}

TEST(Curvature, InnerCornerOfAnLShapeIsConcave) {
  cv::Mat img(300, 300, CV_8UC1, cv::Scalar(0));
  cv::rectangle(img, cv::Rect(50, 50, 200, 100), cv::Scalar(255), cv::FILLED);
  cv::rectangle(img, cv::Rect(50, 50, 100, 200), cv::Scalar(255), cv::FILLED);
  ExtractionParams p;
  p.binarise.dilate_px = p.binarise.erode_px = 0;
  const ExtractionResult r = extract_silhouette(frame_of(img), p);
  ASSERT_TRUE(r.ok());
  const auto& s = *r.silhouette;
  double at_inner = 0;
  for (std::size_t i = 0; i < s.contour.size(); ++i)
    if (cv::norm(cv::Point2d(s.contour[i]) - cv::Point2d(149, 149)) < 1.5) at_inner = std::min(at_inner, s.curvature[i]);
  EXPECT_LT(at_inner, -0.05);
  EXPECT_NEAR(mean_curvature_away_from(s, {{50, 50}, {249, 50}, {249, 149}, {149, 149}, {149, 249}, {50, 249}}, 17), 0.0,
              1e-9);
}
