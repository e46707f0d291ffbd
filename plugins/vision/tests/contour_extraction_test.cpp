#include <cmath>
#include <limits>
#include <memory>

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "fba/vision/contour_extraction.hpp"
#include "fba/vision/image_set.hpp"
#include "support/build_paths.hpp"
#include "support/data_sets.hpp"

using namespace fba::vision;

namespace {

using fba::test::kDino;

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

// A filled shape rasterised at pixel centres: (x, y) is inside when inside(x, y).
template <class F>
cv::Mat raster(int w, int h, F inside) {
  cv::Mat m(h, w, CV_8UC1, cv::Scalar(0));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (inside(double(x), double(y))) m.at<std::uint8_t>(y, x) = 255;
  return m;
}

fba::Silhouette from_mask(const cv::Mat& mask, const SelectionParams& p = {}) {
  const ExtractionResult r = silhouette_from_mask(mask, frame_of(mask), p);
  if (!r.ok()) throw std::runtime_error(r.error);
  return *r.silhouette;
}

std::uint8_t at(const cv::Mat& m, cv::Point2d p) { return m.at<std::uint8_t>(cv::Point(p)); }

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

TEST(Holes, DefaultMinimumAreaKeepsARealHoleAndFillsASpeck) {
  cv::Mat img = raster(300, 300, [](double x, double y) { return std::hypot(x - 150, y - 150) <= 100; });
  cv::circle(img, {150, 150}, 30, cv::Scalar(0), cv::FILLED);  // a real hole, ~2800 px
  cv::circle(img, {210, 150}, 2, cv::Scalar(0), cv::FILLED);   // a speck of shadow, 13 px
  const fba::Silhouette s = from_mask(img);
  EXPECT_EQ(s.mask.at<std::uint8_t>(150, 150), 0);
  EXPECT_EQ(s.mask.at<std::uint8_t>(150, 210), 255);
  ASSERT_EQ(s.holes.size(), 1u);
  // The hole keeps the object's pixels around it: the mask is the input without the speck.
  cv::Mat expected = img.clone();
  cv::circle(expected, {210, 150}, 2, cv::Scalar(255), cv::FILLED);
  EXPECT_EQ(cv::countNonZero(s.mask != expected), 0);
  SelectionParams fill;
  fill.min_hole_area_px = std::numeric_limits<double>::infinity();
  const fba::Silhouette filled = from_mask(img, fill);
  EXPECT_EQ(filled.mask.at<std::uint8_t>(150, 150), 255);
  EXPECT_TRUE(filled.holes.empty());
}

TEST(Holes, AShadowOnTheObjectIsFilledAHoleShowingTheBackgroundStaysOpen) {
  cv::Mat img(300, 300, CV_8UC1, cv::Scalar(2));
  cv::circle(img, {150, 150}, 120, cv::Scalar(200), cv::FILLED);
  cv::circle(img, {100, 150}, 30, cv::Scalar(3), cv::FILLED);   // see-through: the background
  cv::circle(img, {200, 150}, 30, cv::Scalar(30), cv::FILLED);  // a shadow, below the threshold too
  ExtractionParams p;
  p.binarise.dilate_px = p.binarise.erode_px = 0;
  ExtractionResult r = extract_silhouette(frame_of(img), p);
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_EQ(r.silhouette->mask.at<std::uint8_t>(150, 100), 0);
  EXPECT_EQ(r.silhouette->mask.at<std::uint8_t>(150, 200), 255);
  EXPECT_EQ(r.silhouette->holes.size(), 1u);
  p.selection.hole_background_tolerance = 1;  // off: both stay open
  r = extract_silhouette(frame_of(img), p);
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_EQ(r.silhouette->mask.at<std::uint8_t>(150, 200), 0);
  EXPECT_EQ(r.silhouette->holes.size(), 2u);
}

TEST(Holes, DinoViewsKeepNoHoleTheirShadowsAreFilled) {
  // The dino's binarised masks have dark creases and shadows of up to 1,200 px inside the body;
  // none of them is a see-through hole.
  const ImageSet set = ImageSet::load_middlebury(kDino + "/dinoSR_par.txt");
  for (std::size_t i = 0; i < set.size(); ++i) {
    const ExtractionResult r = extract_silhouette(std::make_shared<const fba::Frame>(set.load_frame(i)));
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_TRUE(r.silhouette->holes.empty()) << set[i].name;
  }
}

TEST(Curvature, DiscOfRadius150IsWithin5PercentOfOneOverRadiusAtEveryPoint) {
  const cv::Point2d c(200, 200);
  const cv::Mat img = raster(400, 400, [&](double x, double y) { return std::hypot(x - c.x, y - c.y) <= 150; });
  const fba::Silhouette s = from_mask(img);
  ASSERT_NEAR(s.contour.size(), 2 * M_PI * 150, 10);  // one point per pixel of arc
  ASSERT_EQ(s.curvature.size(), s.contour.size());
  ASSERT_EQ(s.tangents.size(), s.contour.size());
  ASSERT_EQ(s.normals.size(), s.contour.size());
  EXPECT_TRUE(s.metric_curvature.empty());  // no depth given
  for (std::size_t i = 0; i < s.contour.size(); ++i) {
    EXPECT_NEAR(s.curvature[i], 1.0 / 150, 0.05 / 150) << s.contour[i];
    const cv::Point2d radial = (s.contour[i] - c) / cv::norm(s.contour[i] - c);
    EXPECT_GT(s.normals[i].dot(radial), std::cos(0.02)) << s.contour[i];  // outward, within ~1 degree
    EXPECT_NEAR(s.tangents[i].dot(s.normals[i]), 0.0, 1e-12);
    EXPECT_NEAR(cv::norm(s.tangents[i]), 1.0, 1e-12);
  }
  // Neither the sign nor the normals depend on the contour's direction.
  std::vector<std::vector<cv::Point>> cs;
  cv::findContours(img, cs, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  ASSERT_EQ(cs.size(), 1u);
  const fba::Outline reversed = describe_outline({cs[0].rbegin(), cs[0].rend()}, false, SelectionParams{}.curvature_scale_px);
  for (std::size_t i = 0; i < reversed.contour.size(); ++i) {
    EXPECT_NEAR(reversed.curvature[i], 1.0 / 150, 0.05 / 150);
    EXPECT_GT(reversed.normals[i].dot(reversed.contour[i] - c), 0);
  }
}

TEST(Curvature, EllipseMatchesTheAnalyticCurvatureAtEveryPoint) {
  const double a = 180, b = 120;  // radius of curvature 80 .. 270 px
  const cv::Point2d c(250, 200);
  const cv::Mat img = raster(500, 400, [&](double x, double y) {
    return std::pow((x - c.x) / a, 2) + std::pow((y - c.y) / b, 2) <= 1;
  });
  SelectionParams p;
  p.curvature_scale_px = 24;  // where the pixel steps on the flat sides (r = 270 px) stay below 7%
  const fba::Silhouette s = from_mask(img, p);
  double worst = 0;
  for (std::size_t i = 0; i < s.contour.size(); ++i) {
    // The point's parameter on the ellipse (x, y) = c + (a cos t, b sin t), and the curvature there.
    const double t = std::atan2((s.contour[i].y - c.y) / b, (s.contour[i].x - c.x) / a);
    const double k = a * b / std::pow(a * a * std::pow(std::sin(t), 2) + b * b * std::pow(std::cos(t), 2), 1.5);
    EXPECT_NEAR(s.curvature[i], k, 0.08 * k) << s.contour[i];
    worst = std::max(worst, std::abs(s.curvature[i] / k - 1));
    // The outward normal of the ellipse: the gradient of (x/a)^2 + (y/b)^2.
    cv::Point2d n((s.contour[i].x - c.x) / (a * a), (s.contour[i].y - c.y) / (b * b));
    n /= cv::norm(n);
    EXPECT_GT(s.normals[i].dot(n), std::cos(0.03)) << s.contour[i];
  }
  RecordProperty("worst_relative_error", std::to_string(worst));
}

TEST(Curvature, SquareIsFlatOnTheSidesAndPeaksAtTheCorners) {
  cv::Mat img(300, 300, CV_8UC1, cv::Scalar(0));
  cv::rectangle(img, cv::Rect(50, 50, 200, 200), cv::Scalar(255), cv::FILLED);
  SelectionParams p;
  p.curvature_scale_px = 4;
  const fba::Silhouette s = from_mask(img, p);
  const std::vector<cv::Point2d> corners{{50, 50}, {249, 50}, {249, 249}, {50, 249}};
  std::vector<double> peak(corners.size(), 0);
  double turning = 0;
  for (std::size_t i = 0; i < s.contour.size(); ++i) {
    double d = 1e9;
    for (std::size_t j = 0; j < corners.size(); ++j) {
      const double dj = cv::norm(s.contour[i] - corners[j]);
      d = std::min(d, dj);
      if (dj < 2) peak[j] = std::max(peak[j], s.curvature[i]);
    }
    // Beyond the smoothing kernel's reach (4 sigma) a side is exactly straight.
    if (d > 4 * p.curvature_scale_px + 6) EXPECT_NEAR(s.curvature[i], 0.0, 1e-9) << s.contour[i];
    EXPECT_GT(s.curvature[i], -1e-9) << s.contour[i];  // nowhere concave
    const cv::Point2d& t0 = s.tangents[i];
    const cv::Point2d& t1 = s.tangents[(i + 1) % s.contour.size()];
    turning += std::atan2(t0.cross(t1), t0.dot(t1));
  }
  // A right angle smoothed by a Gaussian of sigma: (pi / 2) / (sigma sqrt(2 pi)) = 0.157 at its peak.
  for (double k : peak) EXPECT_GT(k, 0.12);
  EXPECT_NEAR(std::abs(turning), 2 * M_PI, 1e-9);  // the tangent turns once round a simple closed curve
}

TEST(Curvature, InnerCornerOfAnLShapeIsConcave) {
  cv::Mat img(300, 300, CV_8UC1, cv::Scalar(0));
  cv::rectangle(img, cv::Rect(50, 50, 200, 100), cv::Scalar(255), cv::FILLED);
  cv::rectangle(img, cv::Rect(50, 50, 100, 200), cv::Scalar(255), cv::FILLED);
  SelectionParams p;
  p.curvature_scale_px = 4;
  const fba::Silhouette s = from_mask(img, p);
  double at_inner = 0;
  for (std::size_t i = 0; i < s.contour.size(); ++i)
    if (cv::norm(s.contour[i] - cv::Point2d(149, 149)) < 2) at_inner = std::min(at_inner, s.curvature[i]);
  EXPECT_LT(at_inner, -0.05);
  for (std::size_t i = 0; i < s.contour.size(); ++i) {
    EXPECT_EQ(at(img, s.contour[i] + 3 * s.normals[i]), 0) << s.contour[i];
    EXPECT_EQ(at(img, s.contour[i] - 3 * s.normals[i]), 255) << s.contour[i];
  }
}

TEST(Curvature, AHolesNormalsPointIntoItAndARoundHoleIsConcave) {
  const cv::Point2d c(150, 150);
  const cv::Mat img = raster(300, 300, [&](double x, double y) {
    const double r = std::hypot(x - c.x, y - c.y);
    return r <= 140 && r > 80;
  });
  const fba::Silhouette s = from_mask(img);
  ASSERT_EQ(s.holes.size(), 1u);
  const fba::Outline& h = s.holes[0];
  ASSERT_EQ(h.curvature.size(), h.contour.size());
  for (std::size_t i = 0; i < h.contour.size(); ++i) {
    // The hole's boundary pixels are the object's, at radius ~81.
    EXPECT_NEAR(h.curvature[i], -1.0 / 81, 0.08 / 81) << h.contour[i];
    EXPECT_GT(h.normals[i].dot(c - h.contour[i]) / cv::norm(c - h.contour[i]), std::cos(0.03)) << h.contour[i];
    EXPECT_EQ(at(s.mask, h.contour[i] + 3 * h.normals[i]), 0) << h.contour[i];
    EXPECT_EQ(at(s.mask, h.contour[i] - 3 * h.normals[i]), 255) << h.contour[i];
  }
  for (std::size_t i = 0; i < s.contour.size(); ++i) EXPECT_NEAR(s.curvature[i], 1.0 / 140, 0.05 / 140);
}

TEST(Curvature, MetricCurvatureScalesByFocalLengthOverDepth) {
  const cv::Mat img = raster(400, 400, [](double x, double y) { return std::hypot(x - 200, y - 200) <= 100; });
  auto f = std::make_shared<fba::Frame>();
  f->image = img;
  f->camera.K << 500, 0, 200, 0, 500, 200, 0, 0, 1;
  SelectionParams p;
  p.depth_m = 0.5;  // 100 px at 0.5 m with f = 500 px: a disc of radius 0.1 m
  ExtractionResult r = silhouette_from_mask(img, f, p);
  ASSERT_TRUE(r.ok()) << r.error;
  ASSERT_EQ(r.silhouette->metric_curvature.size(), r.silhouette->contour.size());
  for (std::size_t i = 0; i < r.silhouette->contour.size(); ++i) {
    EXPECT_DOUBLE_EQ(r.silhouette->metric_curvature[i], r.silhouette->curvature[i] * 1000);
    EXPECT_NEAR(r.silhouette->metric_curvature[i], 10.0, 0.8);
  }
  // From the object's position and the camera's pose instead: the camera 0.5 m in front of it.
  p.depth_m = 0;
  p.object_centre = Eigen::Vector3d(0.2, 0, 0);
  f->camera.camera_from_world = Eigen::Translation3d(-0.2, 0, 0.5);
  f->has_pose = true;
  r = silhouette_from_mask(img, f, p);
  ASSERT_TRUE(r.ok()) << r.error;
  ASSERT_EQ(r.silhouette->metric_curvature.size(), r.silhouette->contour.size());
  EXPECT_DOUBLE_EQ(r.silhouette->metric_curvature[0], r.silhouette->curvature[0] * 1000);
  // Without a pose the depth is unknown.
  f->has_pose = false;
  r = silhouette_from_mask(img, f, p);
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_TRUE(r.silhouette->metric_curvature.empty());
}
