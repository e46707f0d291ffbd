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
  static fba::Spec spec() {
    return fba::Spec::sensor("vision.image_set",
                             "Serves a calibrated image set (Middlebury *_par.txt or fba YAML) as camera frames.")
        .optional_input<fba::Pose>("request", "a wanted camera pose (world_from_camera): serves the nearest unserved view")
        .output<fba::Frame>("frame", "an image with intrinsics and the camera pose it was taken from")
        .path_param("file", std::nullopt, "the set: a Middlebury *_par.txt or an fba image-set YAML (docs/image-set-format.md)")
        .param("good_only", true, "Middlebury: keep only the views listed in *_good_silhouette_images.txt beside the file")
        .param("limit", 0, "serve at most this many views; 0 for all").range(0, std::nullopt)
        .event("exhausted", "a view was requested but every view has been served");
  }

  explicit ImageSetSensor(fba::Context& ctx)
      : ctx_(ctx), request_(ctx.input("request")), out_(ctx.output("frame")),
        set_(fba::vision::ImageSet::load(ctx.path("file").string(), ctx.param<bool>("good_only"))) {
    const auto limit = ctx.param<std::int64_t>("limit");
    count_ = limit > 0 ? std::min<std::size_t>(static_cast<std::size_t>(limit), set_.size()) : set_.size();
    if (count_ == 0) throw std::runtime_error("the image set " + ctx.path("file").string() + " has no views");
    // On request, one view per request; otherwise every view in order, as fast as taken.
    if (request_.connected()) ctx.set_trigger({fba::TriggerPolicy::Any, 0});
    ctx.log().info("{} views from {}", count_, ctx.path("file").string());
  }

  void process() override {
    std::size_t index = served_.size();
    if (request_.connected()) {
      const auto next = set_.nearest_unserved_view(request_.get<fba::Pose>().world_from_frame, served_);
      if (!next || served_.size() >= count_) {
        ctx_.emit_event("exhausted", std::to_string(served_.size()) + " views served");
        ctx_.finish();
        return;
      }
      index = *next;
    }
    served_.insert(index);
    auto frame = std::make_shared<fba::Frame>(set_.load_frame(index));
    frame->stamp = static_cast<double>(ctx_.now_ns()) * 1e-9;
    out_.emit(std::shared_ptr<const fba::Frame>(std::move(frame)));
    if (served_.size() >= count_) ctx_.finish();
  }

 private:
  fba::Context& ctx_;
  fba::Input& request_;
  fba::Output& out_;
  const fba::vision::ImageSet set_;
  std::size_t count_ = 0;
  std::set<std::size_t> served_;
};

}  // namespace

FBA_COMPONENT(ImageSetSensor);
