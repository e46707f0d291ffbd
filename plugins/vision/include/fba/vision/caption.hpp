// Titles and legends drawn into the pictures a run writes, so that a picture explains itself when
// it is looked at on its own: what it shows (the object, the view, the scores) in a band above it,
// and what each colour means in a band below it. The one way every picture writer captions.
//
// The bands have fixed heights, so a captioned picture's size follows from the picture's alone
// (captioned_size); text too long for the width is drawn smaller, never cut off.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace fba::vision {

// How a legend entry shows its colour, as the picture draws it.
enum class LegendMark {
  Swatch,  // a filled square: a surface or an area
  Hatch,   // a hatched square: a translucent, hatched area
  Line,    // a line: an outline or a contour
  Dot,     // a disc: a point (a contact, a camera)
};

struct LegendEntry {
  cv::Scalar colour;  // BGR
  std::string label;  // a few words: "thumb contact", "not decided yet"
  LegendMark mark = LegendMark::Swatch;
};

struct Caption {
  std::string title;    // what the picture is: "mustard bottle: the carved model after 5 views"
  std::string details;  // one line of figures: view number, camera position, scores
  std::vector<LegendEntry> legend;
};

// Band heights, pixels: the title and details above, two rows of legend below.
inline constexpr int kCaptionHeaderRows = 46;
inline constexpr int kCaptionLegendRows = 46;

// The size of `picture` once captioned: as wide, and taller by both bands.
cv::Size captioned_size(cv::Size picture);
// The picture (8-bit, 1 or 3 channels; grey is turned BGR) between its title band and its legend
// band. Throws std::invalid_argument for an empty picture or another depth.
cv::Mat captioned(const cv::Mat& picture, const Caption& caption);
// Where the legend band lies in a captioned picture of this size.
cv::Rect legend_band(cv::Size captioned);

// A point as "(0.120, -0.050, 0.300) m": camera positions and the like in details lines.
std::string position_text(double x, double y, double z);

}  // namespace fba::vision
