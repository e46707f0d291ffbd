#include "grasp_pictures.hpp"

#include <cmath>
#include <cstdio>
#include <string>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "fba/vision/caption.hpp"

namespace fba::grasp {

namespace {

const cv::Scalar kContact[3] = {{40, 40, 230}, {40, 170, 40}, {230, 120, 30}};  // as the model picture's
const cv::Scalar kApproach{0, 200, 230};

std::string fixed(double v) {
  char s[32];
  std::snprintf(s, sizeof s, "%.3f", v);
  return s;
}

// The grasp drawn over the last camera image: each contact, its inward normal (an arrow into the
// object) and its finger's direction (the approach, ending on it).
cv::Mat grasp_on_image(const Grasp& g, const Frame& frame, const std::string& object) {
  cv::Mat image = frame.image.clone();
  if (image.channels() == 1) cv::cvtColor(image, image, cv::COLOR_GRAY2BGR);
  if (image.depth() != CV_8U) image.convertTo(image, CV_8U, 1.0 / 256);
  const Eigen::Matrix<double, 3, 4> P = frame.camera.projection();
  auto pixel = [&](const Eigen::Vector3d& x) {
    const Eigen::Vector3d h = P * x.homogeneous();
    return cv::Point(static_cast<int>(std::lround(h.x() / h.z())), static_cast<int>(std::lround(h.y() / h.z())));
  };
  for (std::size_t i = 0; i < 3; ++i) {
    const auto& c = g.contacts[i];
    cv::arrowedLine(image, pixel(c.position - g.approach.normalized() * 0.05), pixel(c.position), kApproach, 2, cv::LINE_AA, 0, 0.2);
    cv::arrowedLine(image, pixel(c.position - c.normal.normalized() * 0.03), pixel(c.position), kContact[i], 2, cv::LINE_AA, 0, 0.3);
    cv::circle(image, pixel(c.position), 6, kContact[i], cv::FILLED, cv::LINE_AA);
  }
  const Eigen::Vector3d eye = frame.camera.centre_in_world();
  vision::Caption caption;
  caption.title = object + ": the grasp selected, over the last view";
  caption.details = "view " + std::to_string(g.views.size()) + " (frame " + std::to_string(frame.index) + ") from " +
                    vision::position_text(eye.x(), eye.y(), eye.z()) + "; total " + fixed(g.scores.total) + " (S1 " +
                    fixed(g.scores.symmetry) + ", S3 " + fixed(g.scores.safety_margin) + ", S4 " + fixed(g.scores.curvature) + ")";
  caption.legend = {{kContact[0], "thumb", vision::LegendMark::Dot},
                    {kContact[1], "finger 1", vision::LegendMark::Dot},
                    {kContact[2], "finger 2", vision::LegendMark::Dot},
                    {kApproach, "approach", vision::LegendMark::Line},
                    {{200, 200, 200}, "arrow: contact normal, into the object", vision::LegendMark::Line}};
  return vision::captioned(image, caption);
}

void write(const std::filesystem::path& file, const cv::Mat& picture, spdlog::logger& log) {
  if (!cv::imwrite(file.string(), picture)) log.error("could not write {}", file.string());
}

}  // namespace

void write_loop_pictures(const std::filesystem::path& dir, const Octree& model, const vision::ModelPictureOptions& options,
                         const std::shared_ptr<const Frame>& last_frame, spdlog::logger& log) {
  try {
    write(dir / "grasp_model.png", vision::model_picture(model, options), log);
    write(dir / "views.png", vision::views_picture(model, options), log);
    if (options.grasp && last_frame && !last_frame->image.empty())
      write(dir / "grasp_view.png", grasp_on_image(*options.grasp, *last_frame, options.object.empty() ? "the object" : options.object), log);
  } catch (const std::exception& e) {  // a picture lost is reported; the run's outcome stands
    log.error("could not draw the loop's pictures in {}: {}", dir.string(), e.what());
  }
}

}  // namespace fba::grasp
