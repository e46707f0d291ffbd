// vision.image_set: a calibrated set of images on disk served as camera frames, in order or,
// when an exploration loop asks for a viewpoint, the nearest view not yet served.
#include <set>

#include <fba/component.hpp>
#include <fba/types/frame.hpp>
#include <fba/types/pose.hpp>

#include "fba/vision/image_set.hpp"

namespace {

class ImageSetSensor final : public fba::Component {
 public:
  static constexpr fba::OptionalIn<fba::Pose> kRequest{
      "request", "a wanted camera pose (world_from_camera): serves the nearest unserved view"};
  static constexpr fba::Out<fba::Frame> kFrame{"frame", "an image with intrinsics and the camera pose it was taken from"};
  static constexpr fba::Param<std::filesystem::path> kFile{
      "file", fba::required, "the set: a Middlebury *_par.txt or an fba image-set YAML (docs/image-set-format.md)"};
  static constexpr fba::Param<bool> kGoodOnly{
      "good_only", true, "Middlebury: keep only the views listed in *_good_silhouette_images.txt beside the file"};
  static constexpr auto kLimit = fba::Param<std::int64_t>("limit", 0, "serve at most this many views; 0 for all").at_least(0);
  static constexpr fba::EventOut kExhausted{"exhausted", "a view was requested but every view has been served"};

  static fba::Spec spec() {
    return fba::Spec::sensor("vision.image_set", "Serves a calibrated image set (Middlebury *_par.txt or fba YAML) as camera frames.")
        .add(kRequest, kFrame, kFile, kGoodOnly, kLimit, kExhausted)
        // The set is read (its text and each image's size) when the task is checked, so a
        // malformed or inconsistent set fails `fba-run --check` at this parameter.
        .check(kFile, [](const fba::ParamValues& p) {
          try {
            fba::vision::ImageSet::load(p(kFile).string(), p(kGoodOnly));
            return std::string();
          } catch (const std::exception& e) {  // FormatError, or the file system's own error
            return std::string(e.what());
          }
        });
  }

  explicit ImageSetSensor(fba::Context& ctx)
      : ctx_(ctx), set_(fba::vision::ImageSet::load(ctx(kFile).string(), ctx(kGoodOnly))) {
    const auto limit = ctx(kLimit);
    count_ = limit > 0 ? std::min<std::size_t>(static_cast<std::size_t>(limit), set_.size()) : set_.size();
    if (count_ == 0) throw std::runtime_error("the image set " + ctx(kFile).string() + " has no views");
    // On request, one view per request; otherwise every view in order, as fast as taken.
    if (ctx(kRequest).connected()) ctx.set_trigger({fba::TriggerPolicy::Any, 0});
    ctx.log().info("{} views from {}", count_, ctx(kFile).string());
  }

  void process() override {
    std::size_t index = served_.size();
    if (const auto request = ctx_(kRequest); request.connected()) {
      const auto next = set_.nearest_unserved_view(request.get().world_from_frame, served_);
      if (!next || served_.size() >= count_) {
        ctx_.emit(kExhausted, std::to_string(served_.size()) + " views served");
        ctx_.finish();
        return;
      }
      index = *next;
    }
    served_.insert(index);
    auto frame = std::make_shared<fba::Frame>(set_.load_frame(index));
    frame->stamp = static_cast<double>(ctx_.now_ns()) * 1e-9;
    ctx_(kFrame).emit(std::shared_ptr<const fba::Frame>(std::move(frame)));
    if (served_.size() >= count_) ctx_.finish();
  }

 private:
  fba::Context& ctx_;
  const fba::vision::ImageSet set_;
  std::size_t count_ = 0;
  std::set<std::size_t> served_;
};

}  // namespace

FBA_COMPONENT(ImageSetSensor);
