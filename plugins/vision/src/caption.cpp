#include "fba/vision/caption.hpp"

#include <algorithm>
#include <cstdio>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

namespace fba::vision {

namespace {

constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr int kPad = 8;                       // pixels from the picture's sides
constexpr int kMark = 14;                     // a legend mark's square
const cv::Scalar kBand{38, 38, 38};           // both bands: dark, so that light text and marks show
const cv::Scalar kText{245, 245, 245};
const cv::Scalar kSoftText{190, 190, 190};

int text_width(const std::string& s, double scale, int thickness) {
  int baseline = 0;
  return cv::getTextSize(s, kFont, scale, thickness, &baseline).width;
}

// The largest scale up to `scale` at which `s` fits `width` (a floor keeps it legible).
double fitting(const std::string& s, double scale, int thickness, int width) {
  while (scale > 0.3 && text_width(s, scale, thickness) > width) scale *= 0.92;
  return scale;
}

int entry_width(const LegendEntry& e, double scale) { return kMark + 5 + text_width(e.label, scale, 1) + 16; }

// The entries flowed into rows at this scale: the index each row starts at.
std::vector<std::size_t> rows_of(const std::vector<LegendEntry>& legend, double scale, int width) {
  std::vector<std::size_t> starts{0};
  int x = 0;
  for (std::size_t i = 0; i < legend.size(); ++i) {
    const int w = entry_width(legend[i], scale);
    if (x > 0 && x + w > width) {
      starts.push_back(i);
      x = 0;
    }
    x += w;
  }
  return starts;
}

void draw_mark(cv::Mat& band, cv::Point at, const LegendEntry& e) {
  const cv::Rect box(at.x, at.y - kMark + 2, kMark, kMark);
  switch (e.mark) {
    case LegendMark::Swatch:
      cv::rectangle(band, box, e.colour, cv::FILLED);
      break;
    case LegendMark::Hatch: {
      cv::rectangle(band, box, e.colour * 0.45 + kBand * 0.55, cv::FILLED);
      cv::Mat square = band(box);  // lines clipped to the square
      for (int d = -kMark; d < kMark; d += 4) cv::line(square, {d, 0}, {d + kMark, kMark}, e.colour, 1, cv::LINE_AA);
      cv::rectangle(band, box, e.colour, 1);
      break;
    }
    case LegendMark::Line:
      cv::line(band, {box.x, box.y + kMark / 2}, {box.x + kMark, box.y + kMark / 2}, e.colour, 3, cv::LINE_AA);
      break;
    case LegendMark::Dot:
      cv::circle(band, {box.x + kMark / 2, box.y + kMark / 2}, kMark / 2 - 1, e.colour, cv::FILLED, cv::LINE_AA);
      break;
  }
}

void draw_legend(cv::Mat band, const std::vector<LegendEntry>& legend) {
  const int width = band.cols - 2 * kPad;
  double scale = 0.45;
  while (scale > 0.3 && rows_of(legend, scale, width).size() > 2) scale *= 0.92;
  const std::vector<std::size_t> starts = rows_of(legend, scale, width);
  for (std::size_t r = 0; r < starts.size() && r < 2; ++r) {
    const std::size_t end = r + 1 < starts.size() ? starts[r + 1] : legend.size();
    int x = kPad;
    const int y = 18 + 20 * static_cast<int>(r);
    for (std::size_t i = starts[r]; i < end; ++i) {
      draw_mark(band, {x, y}, legend[i]);
      cv::putText(band, legend[i].label, {x + kMark + 5, y}, kFont, scale, kText, 1, cv::LINE_AA);
      x += entry_width(legend[i], scale);
    }
  }
}

}  // namespace

cv::Size captioned_size(cv::Size picture) { return {picture.width, picture.height + kCaptionHeaderRows + kCaptionLegendRows}; }

cv::Rect legend_band(cv::Size captioned) {
  return {0, captioned.height - kCaptionLegendRows, captioned.width, kCaptionLegendRows};
}

cv::Mat captioned(const cv::Mat& picture, const Caption& caption) {
  if (picture.empty()) throw std::invalid_argument("captioned: the picture is empty");
  if (picture.depth() != CV_8U || (picture.channels() != 1 && picture.channels() != 3))
    throw std::invalid_argument("captioned: the picture must be 8-bit grey or BGR");
  cv::Mat out(captioned_size(picture.size()), CV_8UC3, kBand);
  cv::Mat body = out(cv::Rect(0, kCaptionHeaderRows, picture.cols, picture.rows));
  if (picture.channels() == 1) cv::cvtColor(picture, body, cv::COLOR_GRAY2BGR);
  else picture.copyTo(body);

  const int width = picture.cols - 2 * kPad;
  cv::putText(out, caption.title, {kPad, 19}, kFont, fitting(caption.title, 0.58, 2, width), kText, 2, cv::LINE_AA);
  cv::putText(out, caption.details, {kPad, 39}, kFont, fitting(caption.details, 0.45, 1, width), kSoftText, 1, cv::LINE_AA);
  draw_legend(out(legend_band(out.size())), caption.legend);
  return out;
}

std::string position_text(double x, double y, double z) {
  char s[96];
  std::snprintf(s, sizeof s, "(%.3f, %.3f, %.3f) m", x, y, z);
  return s;
}

}  // namespace fba::vision
