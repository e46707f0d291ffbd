// vision.contour_extraction: from a camera frame to the target's silhouette (mask with its holes,
// outlines resampled at 1 px with tangents, outward normals and curvature). A frame with no usable target is an event, not a failure: exploration goes on.
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <fba/component.hpp>
#include <fba/types/frame.hpp>
#include <fba/types/silhouette.hpp>

#include "fba/vision/caption.hpp"
#include "fba/vision/contour_extraction.hpp"
#include "fba/vision/model_picture.hpp"

namespace {

class ContourExtraction final : public fba::Component {
 public:
  static constexpr fba::In<fba::Frame> kFrame{"frame", "a camera frame"};
  static constexpr fba::Out<fba::Silhouette> kSilhouette{"silhouette", "the target's mask, outer contour and holes with per-point tangent, normal and curvature; the frame's time stamp"};
  static constexpr auto kMethod = fba::Param<std::string>("method", "fixed", "binarisation").choices({"fixed", "otsu"});
  static constexpr auto kThreshold = fba::Param<double>("threshold", 0.19, "fixed: foreground above this share of full scale").range(0, 1);
  static constexpr fba::Param<bool> kDarkObject{"dark_object", false, "the object is darker than the background"};
  static constexpr auto kDilate = fba::Param<int>("dilate", 10, "pixels of dilation after thresholding (closes shadow gaps)").range(0, 100);
  static constexpr auto kErode = fba::Param<int>("erode", 7, "pixels of erosion after dilation").range(0, 100);
  static constexpr auto kOpen = fba::Param<int>("open", 0, "pixels of morphological opening (removes specks)").range(0, 100);
  static constexpr auto kClose = fba::Param<int>("close", 0, "pixels of morphological closing (fills cracks)").range(0, 100);
  static constexpr auto kMinArea = fba::Param<double>("min_area", 200.0, "smallest target area, pixels").at_least(0);
  static constexpr auto kMaxAreaFraction =
      fba::Param<double>("max_area_fraction", 0.95, "largest target area as a share of the image (larger is background)").range(0, 1);
  static constexpr auto kMinHoleArea = fba::Param<double>(
      "min_hole_area", 50.0, "pixels: holes in the target at least this large stay open (carved through); smaller ones are filled")
                                           .at_least(0);
  static constexpr auto kHoleBackgroundTolerance = fba::Param<double>(
      "hole_background_tolerance", 0.02,
      "a hole stays open only when its mean grey is within this share of full scale of the background's (a shadow on the "
      "object is filled); 1: off")
                                                       .range(0, 1);
  static constexpr auto kCurvatureScale = fba::Param<double>(
      "curvature_scale_px", 20.0,
      "sigma (pixels of arc length) of the smoothing before tangents, normals and curvature; pixel steps need a fair share of "
      "the radius: the default keeps a disc of 150 px within 5% of its curvature at every point, smaller lets the steps through")
                                              .range(0.5, 1000);
  static constexpr auto kDepth = fba::Param<double>(
      "depth_m", 0.0, "the object's depth in every frame (metres) for the metric curvature; 0: from object_centre, or none")
                                     .at_least(0);
  static inline const auto kObjectCentre =
      fba::Param<std::vector<double>>("object_centre", {},
                                      "[x, y, z] world metres: the object's depth per frame (from its pose) for the metric "
                                      "curvature; empty: depth_m, or no metric curvature")
          .size({0, 3});
  static constexpr fba::EventOut kNoTarget{"no_target", "no contour passed the selection, or the image was empty or unreadable; payload: why"};
  static constexpr fba::EventOut kLeavesFrame{"leaves_frame", "the target touches the image border on this view; payload: the frame's source and index"};

  static fba::Spec spec() {
    return fba::Spec::filter("vision.contour_extraction",
                             "Binarises a frame, cleans it up, selects the target's contour and describes its outline.")
        .add(kFrame, kSilhouette, kMethod, kThreshold, kDarkObject, kDilate, kErode, kOpen, kClose, kMinArea, kMaxAreaFraction,
             kMinHoleArea, kHoleBackgroundTolerance, kCurvatureScale, kDepth, kObjectCentre, kNoTarget, kLeavesFrame);
  }

  explicit ContourExtraction(fba::Context& ctx) : ctx_(ctx) {
    auto& b = params_.binarise;
    b.method = ctx(kMethod) == "otsu" ? fba::vision::BinariseParams::Method::Otsu : fba::vision::BinariseParams::Method::Fixed;
    b.threshold = ctx(kThreshold);
    b.dark_object = ctx(kDarkObject);
    b.dilate_px = ctx(kDilate);
    b.erode_px = ctx(kErode);
    b.open_px = ctx(kOpen);
    b.close_px = ctx(kClose);
    auto& s = params_.selection;
    s.min_area_px = ctx(kMinArea);
    s.max_area_fraction = ctx(kMaxAreaFraction);
    s.min_hole_area_px = ctx(kMinHoleArea);
    s.hole_background_tolerance = ctx(kHoleBackgroundTolerance);
    s.curvature_scale_px = ctx(kCurvatureScale);
    s.depth_m = ctx(kDepth);
    if (const std::vector<double> c = ctx(kObjectCentre); c.size() == 3) s.object_centre = Eigen::Vector3d(c[0], c[1], c[2]);
    if (!ctx.output_dir().empty()) {
      overlay_dir_ = ctx.output_dir() / "contours";
      std::filesystem::create_directories(overlay_dir_);
    }
  }

  void process() override {
    const auto frame = ctx_(kFrame).share();
    auto result = fba::vision::extract_silhouette(frame, params_);
    const std::string name = view_name(*frame);
    if (!result.ok()) {
      ctx_.log().warn("{}: {}", name, result.error);
      ctx_.emit(kNoTarget, name + ": " + result.error);
      return;
    }
    if (result.silhouette->touches_border) ctx_.emit(kLeavesFrame, name);
    if (!overlay_dir_.empty()) write_overlay(*result.silhouette, name);
    // Stamped with the frame's capture time (the default: the input's stamp), not now.
    ctx_(kSilhouette).emit(std::make_shared<const fba::Silhouette>(std::move(*result.silhouette)));
  }

 private:
  static std::string view_name(const fba::Frame& f) {
    std::string source = std::filesystem::path(f.source).stem().string();
    if (source.empty()) source = "frame";
    return f.index >= 0 ? source + "_" + std::to_string(f.index) : source;
  }

  // The contour and the holes drawn on the image: what a person checks first when carving goes
  // wrong. The caption tells one view's picture from the next: its number in arrival order, its
  // frame and where the camera stood.
  void write_overlay(const fba::Silhouette& s, const std::string& name) {
    cv::Mat image = s.frame->image.clone();
    if (image.channels() == 1) cv::cvtColor(image, image, cv::COLOR_GRAY2BGR);
    if (image.depth() != CV_8U) image.convertTo(image, CV_8U, 1.0 / 256);
    std::vector<std::vector<cv::Point>> holes;
    for (const auto& h : s.holes) holes.emplace_back(h.contour.begin(), h.contour.end());
    cv::polylines(image, std::vector<std::vector<cv::Point>>{{s.contour.begin(), s.contour.end()}}, true, kOuter, 2, cv::LINE_AA);
    cv::polylines(image, holes, true, kHole, 2, cv::LINE_AA);
    ++views_written_;
    fba::vision::Caption caption;
    caption.title = fba::vision::object_name(s.frame->source) + ": view " + std::to_string(views_written_) + ", its contour";
    caption.details = "frame " + name;
    if (s.frame->has_pose) {
      const Eigen::Vector3d eye = s.frame->camera.centre_in_world();
      caption.details += ", camera at " + fba::vision::position_text(eye.x(), eye.y(), eye.z());
    }
    caption.details += ", " + std::to_string(static_cast<long>(cv::countNonZero(s.mask))) + " px of target";
    if (s.touches_border) caption.details += ", touches the image's border";
    caption.legend = {{kOuter, "outer contour", fba::vision::LegendMark::Line}};
    if (!holes.empty()) caption.legend.push_back({kHole, "holes' contours (carved through)", fba::vision::LegendMark::Line});
    const auto file = overlay_dir_ / (name + ".png");
    if (!cv::imwrite(file.string(), fba::vision::captioned(image, caption))) ctx_.log().error("could not write {}", file.string());
  }

  static inline const cv::Scalar kOuter{0, 255, 0};
  static inline const cv::Scalar kHole{255, 0, 255};
  fba::Context& ctx_;
  fba::vision::ExtractionParams params_;
  std::filesystem::path overlay_dir_;
  int views_written_ = 0;  // the overlays' view numbers, in arrival order
};

}  // namespace

FBA_COMPONENT(ContourExtraction);
