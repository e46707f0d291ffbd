// vision.camera: live capture through OpenCV's VideoCapture (a device, a video file, a URL or
// a GStreamer pipeline), with intrinsics from an OpenCV calibration file and, when the arm's
// camera pose is connected, the pose at capture time.
#include <charconv>
#include <map>

#include <opencv2/videoio.hpp>

#include <fba/component.hpp>
#include <fba/types/frame.hpp>
#include <fba/types/pose.hpp>

#include "fba/vision/image_set.hpp"

namespace {

class Camera final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::sensor("vision.camera", "Captures frames with OpenCV VideoCapture: a device index, a video file, a URL or a GStreamer pipeline.")
        .optional_input<fba::Pose>("pose", "the camera's pose (world_from_camera), e.g. from the arm; the newest one is attached to each frame")
        .output<fba::Frame>("frame", "a captured image with intrinsics, distortion and pose")
        .param("source", "0", "a device index (\"0\"), a video file, a URL, or a GStreamer pipeline ending in appsink")
        .param("backend", "any", "VideoCapture backend").choices({"any", "v4l2", "gstreamer", "ffmpeg", "images"})
        .param("calibration", "", "an OpenCV calibration file (YAML/XML: camera_matrix, distortion_coefficients); empty: none, relative to the task file")
        .param("max_frames", 0, "stop after this many frames; 0 for no limit").range(0, std::nullopt)
        .event("lost", "the source stopped delivering frames (end of file, unplugged device); payload: the source")
        .blocking();  // read() waits for the device, at most about a frame period
  }

  explicit Camera(fba::Context& ctx)
      : ctx_(ctx), pose_(ctx.input("pose")), out_(ctx.output("frame")), source_(ctx.param<std::string>("source")),
        max_frames_(ctx.param<std::int64_t>("max_frames")) {
    static const std::map<std::string, int> backends{{"any", cv::CAP_ANY}, {"v4l2", cv::CAP_V4L2}, {"gstreamer", cv::CAP_GSTREAMER},
                                                     {"ffmpeg", cv::CAP_FFMPEG}, {"images", cv::CAP_IMAGES}};
    const int api = backends.at(ctx.param<std::string>("backend"));
    int device = -1;
    const auto [end, ec] = std::from_chars(source_.data(), source_.data() + source_.size(), device);
    const bool is_device = ec == std::errc() && end == source_.data() + source_.size();
    std::string what = source_;
    if (!is_device && source_.find("://") == std::string::npos && source_.find('!') == std::string::npos) {
      std::filesystem::path p(source_);  // a file: relative to the task file
      if (p.is_relative()) p = ctx.task_dir() / p;
      what = p.string();
    }
    const bool opened = is_device ? capture_.open(device, api) : capture_.open(what, api);
    if (!opened || !capture_.isOpened()) throw std::runtime_error("cannot open video source '" + what + "'");
    if (const auto calibration = ctx.param<std::string>("calibration"); !calibration.empty()) {
      std::filesystem::path p(calibration);
      if (p.is_relative()) p = ctx.task_dir() / p;
      camera_ = fba::vision::load_opencv_calibration(p.string());
    }
    ctx.log().info("capturing from {}", what);
  }

  void process() override {
    cv::Mat image;
    if (!capture_.read(image) || image.empty()) {
      ctx_.emit_event("lost", source_);
      ctx_.finish();
      return;
    }
    auto frame = std::make_shared<fba::Frame>();
    frame->image = image;
    frame->camera = camera_;
    if (frame->camera.width == 0) {  // uncalibrated: a nominal pinhole so geometry stays defined
      frame->camera.width = image.cols;
      frame->camera.height = image.rows;
      frame->camera.K << image.cols, 0, image.cols / 2.0, 0, image.cols, image.rows / 2.0, 0, 0, 1;
    }
    if (const fba::Packet* pose = pose_.latest()) {
      frame->camera.camera_from_world = pose->get<fba::Pose>().world_from_frame.inverse();
      frame->has_pose = true;
    }
    frame->stamp = static_cast<double>(ctx_.now_ns()) * 1e-9;
    frame->source = source_;
    frame->index = static_cast<int>(out_.count());
    out_.emit(std::shared_ptr<const fba::Frame>(std::move(frame)));
    if (max_frames_ > 0 && static_cast<std::int64_t>(out_.count()) >= max_frames_) ctx_.finish();
  }

 private:
  fba::Context& ctx_;
  fba::Input& pose_;
  fba::Output& out_;
  const std::string source_;
  const std::int64_t max_frames_;
  cv::VideoCapture capture_;
  fba::CameraModel camera_;
};

}  // namespace

FBA_COMPONENT(Camera);
