// Checks of the pictures a run writes (fba/vision/caption.hpp): the caption's bands hold something
// drawn, and how much of the picture between them is not its background.
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <filesystem>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "fba/vision/caption.hpp"

namespace fba::test {

// Pixels of a region that differ from its first pixel (the band's or the background's colour).
inline int pixels_unlike_corner(const cv::Mat& region) {
  cv::Mat diff;
  cv::absdiff(region, cv::Scalar(region.at<cv::Vec3b>(0, 0)), diff);
  cv::Mat grey;
  cv::transform(diff, grey, cv::Matx13f(1, 1, 1));
  return cv::countNonZero(grey > 0);
}

// The legend band of a captioned picture: share of its pixels drawn on (marks and text).
inline double legend_ink(const cv::Mat& captioned) {
  const cv::Mat band = captioned(vision::legend_band(captioned.size()));
  return double(pixels_unlike_corner(band)) / double(band.total());
}

// The picture between the bands: share of its pixels that are not the background (its top-left
// pixel, which a picture framing its object leaves empty).
inline double object_share(const cv::Mat& captioned) {
  const cv::Mat body = captioned(cv::Rect(0, vision::kCaptionHeaderRows, captioned.cols,
                                          captioned.rows - vision::kCaptionHeaderRows - vision::kCaptionLegendRows));
  return double(pixels_unlike_corner(body)) / double(body.total());
}

// Checks the picture `file`: written, captioned about a picture of `size`, a legend drawn.
inline void expect_captioned(const std::filesystem::path& file, cv::Size size) {
  const cv::Mat picture = cv::imread(file.string());
  if (picture.empty()) {
    ADD_FAILURE() << "no picture " << file;
    return;
  }
  EXPECT_EQ(picture.size(), vision::captioned_size(size)) << file;
  EXPECT_GT(legend_ink(picture), 0.01) << file;
}

// Checks each picture in a run's contours folder as a captioned 640 x 480 view; returns how many
// there are.
inline std::size_t expect_captioned_contours(const std::filesystem::path& folder) {
  std::size_t count = 0;
  for (const auto& f : std::filesystem::directory_iterator(folder)) {
    expect_captioned(f.path(), {640, 480});
    ++count;
  }
  return count;
}

}  // namespace fba::test
