// The views of frames and silhouettes (libs/types/src/image_views.cpp) on the dino images,
// against docs/live-view.md: the picture decodes to the size the view says, fits in 640 pixels,
// and the contours lie on the mask, inside the image.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "fba/vision/contour_extraction.hpp"
#include "fba/vision/image_set.hpp"
#include "support/data_sets.hpp"
#include "view_checks.hpp"

using fba::test::json;
using fba::test::view_of;

namespace {

const fba::vision::ImageSet& dino() {
  static const auto set = fba::vision::ImageSet::load(fba::test::kDinoPar);
  return set;
}

fba::Silhouette dino_silhouette(std::size_t i) {
  const auto r = fba::vision::extract_silhouette(std::make_shared<const fba::Frame>(dino().load_frame(i)));
  if (!r.ok()) throw std::runtime_error(r.error);
  return *r.silhouette;
}

cv::Mat picture(const json& v, int flags) {
  const auto bytes = fba::test::from_base64(v["data"].get<std::string>());
  return cv::imdecode(bytes, flags);
}

// Every contour point inside the image (pixel centres at integer coordinates) and on the mask's
// edge: within 1.5 px of a pixel inside and of one outside.
void expect_contours_on_the_mask(const json& v, const cv::Mat& mask) {
  cv::Mat inside, outside;
  cv::distanceTransform(255 - mask, inside, cv::DIST_L2, 3);  // distance to the nearest mask pixel
  cv::distanceTransform(mask, outside, cv::DIST_L2, 3);
  for (const json& contour : v["contours"]) {
    ASSERT_GE(contour.size(), 3u);
    for (const json& p : contour) {
      ASSERT_TRUE(fba::test::numbers(p, 2));
      const double x = p[0], y = p[1];
      ASSERT_GE(x, -0.5);
      ASSERT_GE(y, -0.5);
      ASSERT_LE(x, mask.cols - 0.5);
      ASSERT_LE(y, mask.rows - 0.5);
      const int c = std::clamp(int(std::lround(x)), 0, mask.cols - 1), r = std::clamp(int(std::lround(y)), 0, mask.rows - 1);
      EXPECT_LE(inside.at<float>(r, c), 1.5f) << x << "," << y;
      EXPECT_LE(outside.at<float>(r, c), 1.5f) << x << "," << y;
    }
  }
}

}  // namespace

TEST(FrameView, IsTheFrameAsAJpegWithTheCameraPose) {
  const fba::Frame f = dino().load_frame(0);
  const json v = view_of(f);
  ASSERT_EQ(v["kind"], "image");
  EXPECT_EQ(v["encoding"], "jpeg");
  EXPECT_EQ(v["width"], f.image.cols);  // 640 x 480 fits as it is
  EXPECT_EQ(v["height"], f.image.rows);
  EXPECT_EQ(v["contours"], json::array());
  const cv::Mat shown = picture(v, cv::IMREAD_COLOR);
  ASSERT_EQ(shown.size(), f.image.size());
  cv::Mat diff;
  cv::absdiff(shown, f.image, diff);
  EXPECT_LT(cv::mean(diff)[0], 4) << "JPEG at quality 80 keeps the picture";
  ASSERT_TRUE(f.has_pose);
  const Eigen::Vector3d centre = f.camera.centre_in_world();
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(v["camera"]["position"][i].get<double>(), centre[i], 1e-5);
  EXPECT_EQ(v["index"], f.index);
}

TEST(FrameView, DownscalesToAtMost640PixelsWideKeepingTheAspect) {
  fba::Frame f = dino().load_frame(1);
  cv::resize(f.image, f.image, cv::Size(1600, 1200), 0, 0, cv::INTER_LINEAR);
  const json v = view_of(f);
  EXPECT_EQ(v["width"], 640);
  EXPECT_EQ(v["height"], 480);
  EXPECT_EQ(v["scale"], 0.4);
  const cv::Mat shown = picture(v, cv::IMREAD_UNCHANGED);
  EXPECT_EQ(shown.cols, 640);
  EXPECT_EQ(shown.rows, 480);
  EXPECT_NEAR(cv::mean(shown)[1], cv::mean(f.image)[1], 3);
}

TEST(FrameView, ShowsGreySixteenBitAndBgraImagesAndNothingForAnEmptyOne) {
  fba::Frame f;
  f.image = cv::Mat(100, 120, CV_16UC1);
  cv::randu(f.image, 0, 4000);
  json v = view_of(f);
  EXPECT_EQ(picture(v, cv::IMREAD_UNCHANGED).channels(), 1);
  f.image = cv::Mat(50, 40, CV_8UC4, cv::Scalar(10, 200, 30, 255));
  v = view_of(f);
  EXPECT_EQ(v["width"], 40);
  EXPECT_FALSE(v.contains("camera")) << "a frame without a pose";
  f.image = cv::Mat();
  EXPECT_TRUE(view_of(f).is_null());
}

TEST(SilhouetteView, IsTheMaskAsAPngWithItsContoursOnIt) {
  const fba::Silhouette s = dino_silhouette(3);
  const json v = view_of(s);
  ASSERT_EQ(v["kind"], "image");
  EXPECT_EQ(v["encoding"], "png");
  const cv::Mat shown = picture(v, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(shown.type(), CV_8UC1);
  ASSERT_EQ(shown.size(), s.mask.size());
  EXPECT_EQ(cv::countNonZero(shown != s.mask), 0) << "the mask, lossless";
  ASSERT_EQ(v["contours"].size(), 1 + s.holes.size());
  EXPECT_EQ(v["holes"], s.holes.size());
  EXPECT_LT(v["contours"][0].size(), s.contour.size()) << "simplified";
  expect_contours_on_the_mask(v, s.mask);
}

TEST(SilhouetteView, DownscaledMaskAndContoursStayTogether) {
  fba::Silhouette s = dino_silhouette(5);
  cv::resize(s.mask, s.mask, cv::Size(), 2, 2, cv::INTER_NEAREST);  // 1280 x 960
  for (auto& p : s.contour) p = (p + cv::Point2d(0.5, 0.5)) * 2 - cv::Point2d(0.5, 0.5);
  for (auto& h : s.holes)
    for (auto& p : h.contour) p = (p + cv::Point2d(0.5, 0.5)) * 2 - cv::Point2d(0.5, 0.5);
  const json v = view_of(s);
  EXPECT_EQ(v["width"], 640);
  EXPECT_EQ(v["height"], 480);
  const cv::Mat shown = picture(v, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(shown.cols, 640);
  expect_contours_on_the_mask(v, shown);
}

TEST(SilhouetteView, ShowsNothingWithoutAMask) { EXPECT_TRUE(view_of(fba::Silhouette{}).is_null()); }
