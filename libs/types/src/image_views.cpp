// libfba_types' views: a frame as a JPEG, a silhouette as its mask (PNG) with its contours, each
// downscaled to fit in kMaxImageSide pixels each way; registered when the library loads
// (image_views.hpp says why frame.hpp refers to the flag).
#include "fba/types/image_views.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "fba/types/frame.hpp"
#include "fba/types/silhouette.hpp"
#include "fba/view.hpp"
#include "view_json.hpp"
#include "views.hpp"

namespace fba::views {

namespace {

std::string base64(const std::vector<uchar>& bytes) {
  static constexpr char kDigits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (unsigned(bytes[i]) << 16) | (unsigned(bytes[i + 1]) << 8) | bytes[i + 2];
    for (int s = 18; s >= 0; s -= 6) out += kDigits[(v >> s) & 63];
  }
  if (const std::size_t rest = bytes.size() - i; rest > 0) {
    const unsigned v = (unsigned(bytes[i]) << 16) | (rest > 1 ? unsigned(bytes[i + 1]) << 8 : 0u);
    out += kDigits[(v >> 18) & 63];
    out += kDigits[(v >> 12) & 63];
    out += rest > 1 ? kDigits[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

// The factor that fits a width x height image in kMaxImageSide pixels each way (at most 1).
double fit(int width, int height) {
  return std::min({1.0, double(kMaxImageSide) / width, double(kMaxImageSide) / height});
}

cv::Mat downscaled(const cv::Mat& image, double scale) {
  if (scale >= 1) return image;
  cv::Mat out;
  const cv::Size size(std::max(1, int(std::lround(image.cols * scale))), std::max(1, int(std::lround(image.rows * scale))));
  cv::resize(image, out, size, 0, 0, cv::INTER_AREA);
  return out;
}

// An image as 8-bit grey or BGR, as a JPEG holds it: other depths stretched over their range,
// BGRA without its alpha, other channel counts by their first channel. Empty for an empty image.
cv::Mat displayable(const cv::Mat& image) {
  if (image.empty() || image.dims != 2) return {};
  cv::Mat img = image;
  if (img.channels() == 4) cv::cvtColor(img, img, cv::COLOR_BGRA2BGR);
  else if (img.channels() != 1 && img.channels() != 3) cv::extractChannel(img, img, 0);
  if (img.depth() != CV_8U) {
    double lo = 0, hi = 0;
    cv::minMaxLoc(img.reshape(1), &lo, &hi);
    const double gain = hi > lo && std::isfinite(hi - lo) ? 255.0 / (hi - lo) : 0.0;
    img.convertTo(img, CV_8U, gain, -lo * gain);
  }
  return img;
}

json image_json(const cv::Mat& shown, const char* format, const std::vector<int>& encode_params) {
  std::vector<uchar> bytes;
  if (!cv::imencode(format, shown, bytes, encode_params)) throw std::runtime_error("imencode failed");
  return {{"kind", "image"},
          {"width", shown.cols},
          {"height", shown.rows},
          {"encoding", format == std::string(".png") ? "png" : "jpeg"},
          {"data", base64(bytes)},
          {"contours", json::array()}};
}

// One closed contour in the shown image's pixels: pixel centres at integer coordinates, so x in
// the source is (x + 1/2) scale - 1/2 here; simplified to within half a shown pixel.
json polyline(const std::vector<cv::Point2d>& contour, double scale) {
  std::vector<cv::Point2f> points, simplified;
  points.reserve(contour.size());
  for (const cv::Point2d& p : contour)
    if (std::isfinite(p.x) && std::isfinite(p.y))
      points.emplace_back(float((p.x + 0.5) * scale - 0.5), float((p.y + 0.5) * scale - 0.5));
  if (points.size() >= 3) cv::approxPolyDP(points, simplified, 0.5, true);
  else simplified = points;
  json out = json::array();
  for (const cv::Point2f& p : simplified) out.push_back(json::array({number(p.x, kPixels), number(p.y, kPixels)}));
  return out;
}

void describe_frame(json& v, const Frame& f, double scale) {
  v["scale"] = number(scale, kUnit);  // shown pixels per source pixel
  v["source"] = f.source;
  v["index"] = f.index;
  v["stamp"] = number(f.stamp, kUnit);
  // The camera's pose (world_from_camera; OpenCV's camera axes: x right, y down, z forward).
  if (f.has_pose) v["camera"] = pose(f.camera.camera_from_world.inverse());
}

}  // namespace

std::string frame_view(const Packet& p) {
  try {
    const Frame& f = p.get<Frame>();
    const cv::Mat img = displayable(f.image);
    if (img.empty()) return {};
    const double scale = fit(img.cols, img.rows);
    json v = image_json(downscaled(img, scale), ".jpg", {cv::IMWRITE_JPEG_QUALITY, 80});
    describe_frame(v, f, scale);
    return dump(v);
  } catch (...) {  // a view is shown or not, never thrown from (views.hpp)
    return {};
  }
}

std::string silhouette_view(const Packet& p) {
  try {
    const Silhouette& s = p.get<Silhouette>();
    cv::Mat mask = displayable(s.mask);
    if (mask.empty()) return {};
    if (mask.channels() != 1) cv::cvtColor(mask, mask, cv::COLOR_BGR2GRAY);
    const double scale = fit(mask.cols, mask.rows);
    cv::Mat shown = downscaled(mask, scale);
    cv::threshold(shown, shown, 127, 255, cv::THRESH_BINARY);  // a mask stays a mask when averaged down
    json v = image_json(shown, ".png", {cv::IMWRITE_PNG_COMPRESSION, 6});
    json& contours = v["contours"];
    if (!s.contour.empty()) contours.push_back(polyline(s.contour, scale));
    for (const Outline& hole : s.holes)
      if (!hole.contour.empty()) contours.push_back(polyline(hole.contour, scale));
    v["holes"] = s.holes.size();  // the contours after the first, the outer one
    v["touches_border"] = s.touches_border;
    if (s.frame) describe_frame(v, *s.frame, scale);
    else v["scale"] = number(scale, kUnit);
    return dump(v);
  } catch (...) {
    return {};
  }
}

}  // namespace fba::views

namespace fba::types_detail {

const bool image_views_registered = [] {
  register_view(type_of<Frame>()->name, &views::frame_view);
  register_view(type_of<Silhouette>()->name, &views::silhouette_view);
  return true;
}();

}  // namespace fba::types_detail
