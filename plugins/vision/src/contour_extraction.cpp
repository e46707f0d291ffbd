#include "fba/vision/contour_extraction.hpp"

#include <cmath>
#include <stdexcept>

#include <Eigen/Core>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

namespace fba::vision {

namespace {

cv::Mat disc(int radius) {
  return cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * radius + 1, 2 * radius + 1));
}

void check(const BinariseParams& p) {
  if (!(p.threshold >= 0 && p.threshold <= 1))
    throw std::invalid_argument("BinariseParams.threshold: expected 0..1, found " + std::to_string(p.threshold));
  if (p.dilate_px < 0 || p.erode_px < 0 || p.open_px < 0 || p.close_px < 0)
    throw std::invalid_argument("BinariseParams: expected morphology radii >= 0");
}

bool has_distortion(const cv::Mat& d) { return !d.empty() && cv::countNonZero(d != 0) > 0; }

}  // namespace

cv::Mat binarise(const cv::Mat& image, const BinariseParams& p) {
  check(p);
  if (image.empty()) throw std::invalid_argument("binarise: empty image");
  cv::Mat grey;
  if (image.channels() == 3) cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  else if (image.channels() == 4) cv::cvtColor(image, grey, cv::COLOR_BGRA2GRAY);
  else if (image.channels() == 1) grey = image;
  else throw std::invalid_argument("binarise: expected 1, 3 or 4 channels, found " + std::to_string(image.channels()));
  // Work in 8 bits: Otsu needs it, and 0.19 of full scale is the same cut either way.
  if (grey.depth() == CV_16U) grey.convertTo(grey, CV_8U, 255.0 / 65535.0);
  else if (grey.depth() != CV_8U) throw std::invalid_argument("binarise: expected 8- or 16-bit pixels");

  cv::Mat mask;
  const int type = p.dark_object ? cv::THRESH_BINARY_INV : cv::THRESH_BINARY;
  if (p.method == BinariseParams::Method::Otsu) cv::threshold(grey, mask, 0, 255, type | cv::THRESH_OTSU);
  else cv::threshold(grey, mask, p.threshold * 255.0, 255, type);

  // OpenCV's default borders make dilation and erosion ignore outside pixels, so an object that
  // leaves the image still touches the border after the clean-up.
  if (p.dilate_px > 0) cv::dilate(mask, mask, disc(p.dilate_px));
  if (p.erode_px > 0) cv::erode(mask, mask, disc(p.erode_px));
  if (p.open_px > 0) cv::morphologyEx(mask, mask, cv::MORPH_OPEN, disc(p.open_px));
  if (p.close_px > 0) cv::morphologyEx(mask, mask, cv::MORPH_CLOSE, disc(p.close_px));
  return mask;
}

std::vector<double> contour_curvature(const std::vector<cv::Point>& c, int window) {
  const int n = static_cast<int>(c.size());
  std::vector<double> k(c.size(), 0.0);
  if (n < 3 || window < 1) return k;
  const int w = std::max(1, std::min(window, (n - 1) / 2));
  // Orientation: make "convex" positive whichever way the contour runs.
  double area2 = 0;
  for (int i = 0; i < n; ++i) {
    const cv::Point& a = c[static_cast<std::size_t>(i)];
    const cv::Point& b = c[static_cast<std::size_t>((i + 1) % n)];
    area2 += static_cast<double>(a.x) * b.y - static_cast<double>(b.x) * a.y;
  }
  const double orient = area2 >= 0 ? 1.0 : -1.0;
  // Pixel contours are staircases: three raw points can be collinear (or even bend the wrong
  // way) on a circle. Averaging over half the window first removes the steps; straight edges
  // stay straight.
  const int h = std::max(1, w / 2);
  std::vector<cv::Point2d> s(c.size());
  for (int i = 0; i < n; ++i) {
    cv::Point2d sum(0, 0);
    for (int j = -h; j <= h; ++j) sum += cv::Point2d(c[static_cast<std::size_t>(((i + j) % n + n) % n)]);
    s[static_cast<std::size_t>(i)] = sum / double(2 * h + 1);
  }
  for (int i = 0; i < n; ++i) {
    const cv::Point2d p0 = s[static_cast<std::size_t>((i - w + n) % n)];
    const cv::Point2d p1 = s[static_cast<std::size_t>(i)];
    const cv::Point2d p2 = s[static_cast<std::size_t>((i + w) % n)];
    const cv::Point2d a = p1 - p0, b = p2 - p1, d = p2 - p0;
    const double denom = std::sqrt(a.dot(a) * b.dot(b) * d.dot(d));
    const double cross = a.x * b.y - a.y * b.x;
    // Menger curvature: 1 / radius of the circle through the three points. Rounding leaves
    // ~1e-15 on straight edges; call that straight.
    k[static_cast<std::size_t>(i)] = denom > 0 && std::abs(cross) > 1e-9 ? orient * 2.0 * cross / denom : 0.0;
  }
  return k;
}

std::optional<std::size_t> select_target(const std::vector<std::vector<cv::Point>>& contours, cv::Size size,
                                         const SelectionParams& p) {
  const cv::Point2d target = p.near_point.value_or(cv::Point2d(size.width / 2.0, size.height / 2.0));
  const double max_area = p.max_area_fraction * size.area();
  std::optional<std::size_t> best;
  double best_dist = std::numeric_limits<double>::infinity(), best_area = 0;
  for (std::size_t i = 0; i < contours.size(); ++i) {
    const double area = cv::contourArea(contours[i]);
    if (area < p.min_area_px || area > max_area) continue;
    // Signed distance: negative inside, so a contour containing the point always wins; among
    // contours at the same distance the larger one.
    const double dist = -cv::pointPolygonTest(contours[i], cv::Point2f(target), true);
    const double d = std::max(dist, 0.0);
    if (d < best_dist || (d == best_dist && area > best_area)) best = i, best_dist = d, best_area = area;
  }
  return best;
}

ExtractionResult silhouette_from_mask(const cv::Mat& mask_in, std::shared_ptr<const fba::Frame> frame,
                                      const SelectionParams& p) {
  ExtractionResult r;
  if (mask_in.empty()) {
    r.error = "empty mask";
    return r;
  }
  if (mask_in.type() != CV_8UC1) {
    r.error = "expected an 8-bit single-channel mask";
    return r;
  }
  std::vector<std::vector<cv::Point>> contours;
  std::vector<cv::Vec4i> hierarchy;
  cv::findContours(mask_in, contours, hierarchy, cv::RETR_CCOMP, cv::CHAIN_APPROX_NONE);
  std::vector<std::vector<cv::Point>> outer;
  std::vector<int> outer_index;
  for (std::size_t i = 0; i < contours.size(); ++i)
    if (hierarchy[i][3] < 0) outer.push_back(contours[i]), outer_index.push_back(static_cast<int>(i));
  const auto sel = select_target(outer, mask_in.size(), p);
  if (!sel) {
    r.error = "no contour passes the selection (" + std::to_string(outer.size()) + " outer contours, min area " +
              std::to_string(p.min_area_px) + " px, max area fraction " + std::to_string(p.max_area_fraction) + ")";
    return r;
  }
  const int ci = outer_index[*sel];
  fba::Silhouette s;
  s.mask = cv::Mat::zeros(mask_in.size(), CV_8UC1);
  cv::drawContours(s.mask, contours, ci, cv::Scalar(255), cv::FILLED);
  for (int h = hierarchy[static_cast<std::size_t>(ci)][2]; h >= 0; h = hierarchy[static_cast<std::size_t>(h)][0])
    if (cv::contourArea(contours[static_cast<std::size_t>(h)]) >= p.min_hole_area_px) {
      cv::drawContours(s.mask, contours, h, cv::Scalar(0), cv::FILLED);
      // drawContours fills the hole's boundary pixels too; they belong to the object.
      cv::drawContours(s.mask, contours, h, cv::Scalar(255), 1);
    }
  s.contour = contours[static_cast<std::size_t>(ci)];
  s.curvature = contour_curvature(s.contour, p.curvature_window);
  const int W = mask_in.cols - 1, H = mask_in.rows - 1;
  for (const cv::Point& q : s.contour)
    if (q.x <= 0 || q.y <= 0 || q.x >= W || q.y >= H) {
      s.touches_border = true;
      break;
    }
  s.frame = std::move(frame);
  r.silhouette = std::move(s);
  return r;
}

ExtractionResult extract_silhouette(std::shared_ptr<const fba::Frame> frame, const ExtractionParams& p) {
  ExtractionResult r;
  if (!frame) {
    r.error = "no frame";
    return r;
  }
  if (frame->image.empty()) {
    r.error = "empty image" + (frame->source.empty() ? std::string() : " (" + frame->source + ")");
    return r;
  }
  if (frame->image.depth() != CV_8U && frame->image.depth() != CV_16U) {
    r.error = "expected 8- or 16-bit pixels" + (frame->source.empty() ? std::string() : " (" + frame->source + ")");
    return r;
  }
  std::shared_ptr<const fba::Frame> used = frame;
  if (has_distortion(frame->camera.distortion)) {
    auto undist = std::make_shared<fba::Frame>(*frame);
    cv::Mat K;
    cv::eigen2cv(frame->camera.K, K);
    cv::undistort(frame->image, undist->image, K, frame->camera.distortion);
    undist->camera.distortion = cv::Mat();
    used = undist;
  }
  const cv::Mat mask = binarise(used->image, p.binarise);
  r = silhouette_from_mask(mask, used, p.selection);
  if (!r.ok() && !frame->source.empty()) r.error += " (" + frame->source + ")";
  return r;
}

}  // namespace fba::vision
