// vision.camera: live capture through OpenCV's VideoCapture (a device, a video file, a URL or
// a GStreamer pipeline), with intrinsics from an OpenCV calibration file and, when the arm's
// camera pose is connected, the pose at capture time.
#include <atomic>
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
  static constexpr fba::OptionalIn<fba::Pose> kPose{
      "pose", "the camera's pose (world_from_camera), e.g. from the arm; the newest one is attached to each frame"};
  static constexpr fba::Out<fba::Frame> kFrame{"frame", "a captured image with intrinsics, distortion and pose"};
  static constexpr fba::Param<std::string> kSource{
      "source", "0", "a device index (\"0\"), a video file, a URL, or a GStreamer pipeline ending in appsink"};
  static constexpr auto kBackend =
      fba::Param<std::string>("backend", "any", "VideoCapture backend").choices({"any", "v4l2", "gstreamer", "ffmpeg", "images"});
  static constexpr fba::Param<std::string> kCalibration{
      "calibration", "",
      "an OpenCV calibration file (YAML/XML: camera_matrix, distortion_coefficients); empty: none, relative to the task file"};
  static constexpr auto kMaxFrames = fba::Param<std::int64_t>("max_frames", 0, "stop after this many frames; 0 for no limit").at_least(0);
  static constexpr auto kReadTimeout =
      fba::Param<double>("read_timeout", 0.5, "FFmpeg sources (files, URLs): seconds a read may wait, so that a stop is seen that soon").range(0.01, 60);
  static constexpr auto kCapture = fba::Param<std::string>(
      "capture", "stream",
      "stream: every frame the source delivers; per_pose: one frame per pose received (a wrist camera in a view "
      "loop, as sim.camera renders one per pose), the frames in between are read and dropped")
      .choices({"stream", "per_pose"});
  static constexpr fba::EventOut kLost{"lost", "the source stopped delivering frames (end of file, unplugged device); payload: the source"};

  static fba::Spec spec() {
    return fba::Spec::sensor("vision.camera", "Captures frames with OpenCV VideoCapture: a device index, a video file, a URL or a GStreamer pipeline.")
        .add(kPose, kFrame, kSource, kBackend, kCalibration, kMaxFrames, kReadTimeout, kCapture, kLost)
        .blocking();  // a read waits for the device, at most read_timeout
  }

  explicit Camera(fba::Context& ctx) : ctx_(ctx), source_(ctx(kSource)), max_frames_(ctx(kMaxFrames)), per_pose_(ctx(kCapture) == "per_pose") {
    static const std::map<std::string, int> backends{{"any", cv::CAP_ANY}, {"v4l2", cv::CAP_V4L2}, {"gstreamer", cv::CAP_GSTREAMER},
                                                     {"ffmpeg", cv::CAP_FFMPEG}, {"images", cv::CAP_IMAGES}};
    const int api = backends.at(ctx(kBackend));
    int device = -1;
    const auto [end, ec] = std::from_chars(source_.data(), source_.data() + source_.size(), device);
    const bool is_device = ec == std::errc() && end == source_.data() + source_.size();
    std::string what = source_;
    if (!is_device && source_.find("://") == std::string::npos && source_.find('!') == std::string::npos) {
      std::filesystem::path p(source_);  // a file: relative to the task file
      if (p.is_relative()) p = ctx.task_dir() / p;
      what = p.string();
    }
    // Bounds each read, so that interrupt() is seen within read_timeout. Only FFmpeg takes the
    // property (other backends refuse to open with it); a V4L2 device delivers a frame per period.
    std::vector<int> props;
    if (api == cv::CAP_FFMPEG) props = {cv::CAP_PROP_READ_TIMEOUT_MSEC, static_cast<int>(ctx(kReadTimeout) * 1000)};
    const bool opened = is_device ? capture_.open(device, api, props) : capture_.open(what, api, props);
    if (!opened || !capture_.isOpened()) throw std::runtime_error("cannot open video source '" + what + "'");
    // One frame per pose must show the camera where the pose says: a queue of older frames in the
    // driver would hand out one taken before the arm arrived.
    if (per_pose_) capture_.set(cv::CAP_PROP_BUFFERSIZE, 1);
    if (const auto calibration = ctx(kCalibration); !calibration.empty()) {
      std::filesystem::path p(calibration);
      if (p.is_relative()) p = ctx.task_dir() / p;
      camera_ = fba::vision::load_opencv_calibration(p.string());
    }
    ctx.log().info("capturing from {}", what);
  }

  void process() override {
    if (interrupted_.load()) return;  // stopping: no new read
    cv::Mat image;
    if (!capture_.read(image) || image.empty()) {
      if (interrupted_.load()) return;  // the read was cut short by the stop, not by the source
      ctx_.emit(kLost, source_);
      ctx_.finish();
      return;
    }
    if (per_pose_ && !ctx_(kPose).has()) return;  // read to keep the source current; no pose, no frame
    auto frame = std::make_shared<fba::Frame>();
    frame->image = image;
    frame->camera = camera_;
    if (frame->camera.width == 0) {  // uncalibrated: a nominal pinhole so geometry stays defined
      frame->camera.width = image.cols;
      frame->camera.height = image.rows;
      frame->camera.K << image.cols, 0, image.cols / 2.0, 0, image.cols, image.rows / 2.0, 0, 0, 1;
    }
    if (const fba::Pose* pose = ctx_(kPose).latest()) {
      frame->camera.camera_from_world = pose->world_from_frame.inverse();
      frame->has_pose = true;
    }
    frame->stamp = static_cast<double>(ctx_.now_ns()) * 1e-9;
    frame->source = source_;
    auto out = ctx_(kFrame);
    frame->index = static_cast<int>(out.count());
    out.emit(std::shared_ptr<const fba::Frame>(std::move(frame)));
    if (max_frames_ > 0 && static_cast<std::int64_t>(out.count()) >= max_frames_) ctx_.finish();
  }

  // From another thread while process() may be in read(): the capture is not touched here (it
  // is not thread-safe); the read returns within read_timeout and process() sees the flag.
  void interrupt() override { interrupted_.store(true); }

 private:
  fba::Context& ctx_;
  const std::string source_;
  const std::int64_t max_frames_;
  const bool per_pose_;
  cv::VideoCapture capture_;
  fba::CameraModel camera_;
  std::atomic<bool> interrupted_{false};
};

}  // namespace

FBA_COMPONENT(Camera);
