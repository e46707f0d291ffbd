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

// Smoothing that removes the zigzag of a pixel chain before the outline is resampled.
constexpr double kStaircaseSigmaPx = 1.0;

bool has_distortion(const cv::Mat& d) { return !d.empty() && cv::countNonZero(d != 0) > 0; }

// The image as 8-bit grey: Otsu needs 8 bits, and 0.19 of full scale is the same cut either way.
cv::Mat grey8(const cv::Mat& image) {
  cv::Mat grey;
  if (image.channels() == 3) cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  else if (image.channels() == 4) cv::cvtColor(image, grey, cv::COLOR_BGRA2GRAY);
  else if (image.channels() == 1) grey = image;
  else throw std::invalid_argument("binarise: expected 1, 3 or 4 channels, found " + std::to_string(image.channels()));
  if (grey.depth() == CV_16U) grey.convertTo(grey, CV_8U, 255.0 / 65535.0);
  else if (grey.depth() != CV_8U) throw std::invalid_argument("binarise: expected 8- or 16-bit pixels");
  return grey;
}

// The object's depth in this frame (camera z, metres), when the parameters tell it.
std::optional<double> object_depth(const fba::Frame* frame, const SelectionParams& p) {
  if (!frame || frame->camera.K(0, 0) <= 0 || frame->camera.K(1, 1) <= 0) return std::nullopt;
  if (p.depth_m > 0) return p.depth_m;
  if (!p.object_centre || !frame->has_pose) return std::nullopt;
  const double z = (frame->camera.camera_from_world * *p.object_centre).z();
  return z > 0 ? std::optional<double>(z) : std::nullopt;  // behind the camera: no meaningful depth
}

}  // namespace

void fill_holes_unlike_background(cv::Mat& mask, const cv::Mat& grey, const SelectionParams& p) {
  if (!(p.hole_background_tolerance < 1)) return;
  std::vector<std::vector<cv::Point>> outer;
  cv::findContours(mask, outer, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
  cv::Mat outside = cv::Mat::zeros(mask.size(), CV_8UC1);
  cv::drawContours(outside, outer, -1, cv::Scalar(255), cv::FILLED);
  outside = outside == 0;
  if (cv::countNonZero(outside) == 0) return;  // no background seen: nothing to compare with
  const double background = cv::mean(grey, outside)[0];
  std::vector<std::vector<cv::Point>> contours;
  std::vector<cv::Vec4i> hierarchy;
  cv::findContours(mask, contours, hierarchy, cv::RETR_CCOMP, cv::CHAIN_APPROX_SIMPLE);
  cv::Mat hole(mask.size(), CV_8UC1);
  for (std::size_t i = 0; i < contours.size(); ++i) {
    if (hierarchy[i][3] < 0 || cv::contourArea(contours[i]) < p.min_hole_area_px) continue;  // not a hole to keep
    hole.setTo(0);
    cv::drawContours(hole, contours, static_cast<int>(i), cv::Scalar(255), cv::FILLED);
    hole &= mask == 0;
    if (std::abs(cv::mean(grey, hole)[0] - background) > p.hole_background_tolerance * 255) mask.setTo(255, hole);
  }
}

cv::Mat binarise(const cv::Mat& image, const BinariseParams& p) {
  check(p);
  if (image.empty()) throw std::invalid_argument("binarise: empty image");
  const cv::Mat grey = grey8(image);

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

namespace {

// The closed polyline through c resampled at equal steps of its arc length, as close to 1 px as a
// whole number of steps allows. Empty when the polyline has no length.
std::vector<cv::Point2d> resample(const std::vector<cv::Point2d>& c) {
  const std::size_t n = c.size();
  std::vector<double> cum(n + 1, 0.0);  // arc length at each point, the closing segment last
  for (std::size_t i = 0; i < n; ++i) cum[i + 1] = cum[i] + cv::norm(c[(i + 1) % n] - c[i]);
  const double length = cum[n];
  if (!(length > 0)) return {};
  const std::size_t m = std::max<std::size_t>(3, static_cast<std::size_t>(std::lround(length)));
  const double step = length / static_cast<double>(m);
  std::vector<cv::Point2d> out(m);
  for (std::size_t k = 0, i = 0; k < m; ++k) {
    const double t = static_cast<double>(k) * step;
    while (i + 1 < n && cum[i + 1] < t) ++i;
    const double seg = cum[i + 1] - cum[i];
    const double f = seg > 0 ? (t - cum[i]) / seg : 0.0;
    out[k] = c[i] + f * (c[(i + 1) % n] - c[i]);
  }
  return out;
}

// Gaussian smoothing of a closed curve along its points (sigma in points).
std::vector<cv::Point2d> smooth(const std::vector<cv::Point2d>& c, double sigma) {
  const long m = static_cast<long>(c.size());
  const int r = static_cast<int>(std::ceil(4 * sigma));
  std::vector<double> g(static_cast<std::size_t>(2 * r + 1));
  double gsum = 0;
  for (int j = -r; j <= r; ++j) gsum += g[static_cast<std::size_t>(j + r)] = std::exp(-0.5 * j * j / (sigma * sigma));
  std::vector<cv::Point2d> out(c.size());
  for (long i = 0; i < m; ++i) {
    cv::Point2d sum(0, 0);
    for (int j = -r; j <= r; ++j) sum += g[static_cast<std::size_t>(j + r)] * c[static_cast<std::size_t>(((i + j) % m + m) % m)];
    out[static_cast<std::size_t>(i)] = sum / gsum;
  }
  return out;
}

}  // namespace

fba::Outline describe_outline(const std::vector<cv::Point>& c, bool hole, double scale_px) {
  if (!(scale_px > 0)) throw std::invalid_argument("describe_outline: expected scale_px > 0, found " + std::to_string(scale_px));
  fba::Outline o;
  const std::vector<cv::Point2d> chain(c.begin(), c.end());
  // An 8-connected chain has steps of 1 and 1.41 px and zigzags on slanted edges: its length runs
  // up to 8% over the outline's, unevenly, and smoothing at a fixed number of points then bends
  // the curve where the chain is longer (a disc's curvature came out 5% high at 20 px scale). So
  // the zigzag is taken out first (sigma 1 px), and the outline resampled by its own arc length.
  const std::vector<cv::Point2d> first = resample(chain);
  if (c.size() >= 3 && !first.empty()) o.contour = resample(smooth(first, kStaircaseSigmaPx));
  if (o.contour.size() < 3) {
    o.contour = chain;
    o.tangents.assign(c.size(), cv::Point2d(0, 0));
    o.normals.assign(c.size(), cv::Point2d(0, 0));
    o.curvature.assign(c.size(), 0.0);
    return o;
  }
  const std::size_t m = o.contour.size();
  const double step = cv::norm(o.contour[1] - o.contour[0]);
  const std::vector<cv::Point2d> sm = smooth(o.contour, scale_px / step);
  const long mm = static_cast<long>(m);
  auto at = [&](long i) { return static_cast<std::size_t>(((i % mm) + mm) % mm); };
  // Which side the polygon's inside is on: with a positive shoelace area it is to the left of
  // the direction of travel, (-t.y, t.x), in these (any) axes.
  double area2 = 0;
  for (std::size_t i = 0; i < m; ++i) area2 += sm[i].cross(sm[(i + 1) % m]);
  const double inside_left = area2 >= 0 ? 1.0 : -1.0;
  // Out of the object: away from the inside of an outer contour, into the inside of a hole's.
  const double out_left = hole ? inside_left : -inside_left;
  o.tangents.resize(m);
  o.normals.resize(m);
  o.curvature.resize(m);
  for (long i = 0; i < mm; ++i) {
    const cv::Point2d d1 = 0.5 * (sm[at(i + 1)] - sm[at(i - 1)]);
    const cv::Point2d d2 = sm[at(i + 1)] - 2.0 * sm[at(i)] + sm[at(i - 1)];
    const double speed = cv::norm(d1);
    const auto k = static_cast<std::size_t>(i);
    if (speed < 1e-12) {  // a spike folded onto itself: no direction
      o.tangents[k] = o.normals[k] = cv::Point2d(0, 0);
      o.curvature[k] = 0;
      continue;
    }
    const cv::Point2d t = d1 / speed;
    o.tangents[k] = t;
    o.normals[k] = out_left * cv::Point2d(-t.y, t.x);
    // d1 x d2 / |d1|^3 turns towards the left normal when positive; convex means the curve turns
    // away from the outward normal.
    o.curvature[k] = -out_left * d1.cross(d2) / (speed * speed * speed);
  }
  return o;
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
  std::vector<int> kept_holes;
  for (int h = hierarchy[static_cast<std::size_t>(ci)][2]; h >= 0; h = hierarchy[static_cast<std::size_t>(h)][0])
    if (cv::contourArea(contours[static_cast<std::size_t>(h)]) >= p.min_hole_area_px) {
      kept_holes.push_back(h);
      cv::drawContours(s.mask, contours, h, cv::Scalar(0), cv::FILLED);
      // drawContours fills the hole's boundary pixels too; they belong to the object.
      cv::drawContours(s.mask, contours, h, cv::Scalar(255), 1);
    }
  static_cast<fba::Outline&>(s) = describe_outline(contours[static_cast<std::size_t>(ci)], false, p.curvature_scale_px);
  for (int h : kept_holes) s.holes.push_back(describe_outline(contours[static_cast<std::size_t>(h)], true, p.curvature_scale_px));
  const int W = mask_in.cols - 1, H = mask_in.rows - 1;
  for (const cv::Point& q : contours[static_cast<std::size_t>(ci)])
    if (q.x <= 0 || q.y <= 0 || q.x >= W || q.y >= H) {
      s.touches_border = true;
      break;
    }
  if (const std::optional<double> depth = object_depth(frame.get(), p)) {
    // A length of l px at depth Z is l * Z / f metres, so a radius too; curvature scales inversely.
    const double per_m = 0.5 * (frame->camera.K(0, 0) + frame->camera.K(1, 1)) / *depth;
    auto metric = [per_m](fba::Outline& o) {
      o.metric_curvature.resize(o.curvature.size());
      for (std::size_t i = 0; i < o.curvature.size(); ++i) o.metric_curvature[i] = o.curvature[i] * per_m;
    };
    metric(s);
    for (auto& h : s.holes) metric(h);
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
  cv::Mat mask = binarise(used->image, p.binarise);
  fill_holes_unlike_background(mask, grey8(used->image), p.selection);
  r = silhouette_from_mask(mask, used, p.selection);
  if (!r.ok() && !frame->source.empty()) r.error += " (" + frame->source + ")";
  return r;
}

}  // namespace fba::vision
