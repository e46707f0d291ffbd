// sim.camera: the simulated twin of a camera. Renders an object mesh (OBJ, PLY, STL...) from
// the pose it receives, or from a ring or an even spread of viewpoints over the upper
// hemisphere, with the given intrinsics: a shaded object on a background, optional noise.
#include <cmath>

#include <fba/component.hpp>
#include <fba/types/frame.hpp>
#include <fba/types/pose.hpp>

#include "fba/geometry/mesh_io.hpp"
#include "fba/geometry/renderer.hpp"
#include "fba/geometry/viewpoints.hpp"

namespace {

constexpr double kDegree = M_PI / 180.0;

class SimCamera final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::sensor("sim.camera", "Renders an object mesh as a calibrated camera would see it (the twin of vision.camera).")
        .optional_input<fba::Pose>("pose", "render from this camera pose (world_from_camera), one frame per pose")
        .output<fba::Frame>("frame", "the rendered image with its intrinsics and pose")
        .path_param("mesh", std::nullopt, "the object: any mesh assimp reads (OBJ, PLY, STL...), metres, z up")
        .param("width", 640, "image width, pixels").range(16, 8192)
        .param("height", 480, "image height, pixels").range(16, 8192)
        .param("fx", 600.0, "focal length, pixels").range(1, std::nullopt)
        .param("fy", 0.0, "vertical focal length, pixels; 0: same as fx").range(0, std::nullopt)
        .param("viewpoints", "hemisphere", "without a pose input: where the views are").choices({"hemisphere", "ring"})
        .param("views", 8, "number of viewpoints").range(1, 10000)
        .param("min_elevation", 0.0, "degrees above the horizon (hemisphere)").range(-90, 90)
        .param("max_elevation", 90.0, "degrees above the horizon (hemisphere); the ring's elevation").range(-90, 90)
        .param("distance", 0.0, "metres from the object's centre; 0: far enough to frame it").range(0, std::nullopt)
        .param("object_grey", 210, "object brightness before shading").range(0, 255)
        .param("background_grey", 25, "background brightness").range(0, 255)
        .param("noise", 0.0, "sensor noise, standard deviation in grey levels").range(0, 100)
        .param("seed", 1, "noise seed");
  }

  explicit SimCamera(fba::Context& ctx)
      : ctx_(ctx), pose_(ctx.input("pose")), out_(ctx.output("frame")), mesh_name_(ctx.path("mesh").stem().string()) {
    auto loaded = fba::geometry::load_mesh_with_warnings(ctx.path("mesh"));
    for (const auto& w : loaded.warnings) ctx.log().info("{}", w);
    mesh_ = std::move(loaded.mesh);
    const int w = ctx.param<int>("width"), h = ctx.param<int>("height");
    const double fx = ctx.param<double>("fx"), fy = ctx.param<double>("fy") > 0 ? ctx.param<double>("fy") : fx;
    camera_ = fba::geometry::make_camera(w, h, fx, fy, (w - 1) / 2.0, (h - 1) / 2.0);
    const auto bounds = fba::geometry::mesh_bounds(mesh_);
    const Eigen::Vector3d centre = bounds.center();
    double distance = ctx.param<double>("distance");
    if (distance == 0) distance = fba::geometry::framing_distance(bounds, w, h, std::min(fx, fy));
    const int n = ctx.param<int>("views");
    const double lo = ctx.param<double>("min_elevation") * kDegree, hi = ctx.param<double>("max_elevation") * kDegree;
    views_ = ctx.param<std::string>("viewpoints") == "ring" ? fba::geometry::ring_views(n, hi, distance, centre)
                                                            : fba::geometry::hemisphere_views(n, lo, hi, distance, centre);
    look_.object_colour = cv::Vec3b::all(static_cast<unsigned char>(ctx.param<int>("object_grey")));
    look_.background_top = look_.background_bottom = cv::Vec3b::all(static_cast<unsigned char>(ctx.param<int>("background_grey")));
    look_.ambient = 0.35;
    look_.diffuse = 0.65;
    look_.noise_sigma = ctx.param<double>("noise");
    look_.seed = static_cast<std::uint64_t>(ctx.param<std::int64_t>("seed"));
    if (pose_.connected()) ctx.set_trigger({fba::TriggerPolicy::Any, 0});
    ctx.log().info("{}: {} triangles, {} viewpoints at {:.3f} m", mesh_name_, mesh_.triangles.size(), views_.size(), distance);
  }

  void process() override {
    fba::CameraModel camera = camera_;
    if (pose_.connected()) {
      camera.camera_from_world = pose_.get<fba::Pose>().world_from_frame.inverse();
    } else {
      camera.camera_from_world = views_[next_++];
      if (next_ == views_.size()) ctx_.finish();
    }
    look_.seed += 1;  // each frame its own noise, the same sequence on every run
    auto frame = std::make_shared<fba::Frame>();
    frame->image = fba::geometry::render(mesh_, camera, look_).colour;
    frame->camera = camera;
    frame->has_pose = true;
    frame->stamp = static_cast<double>(ctx_.now_ns()) * 1e-9;
    frame->source = "sim_" + mesh_name_;
    frame->index = static_cast<int>(out_.count());
    out_.emit(std::shared_ptr<const fba::Frame>(std::move(frame)));
  }

 private:
  fba::Context& ctx_;
  fba::Input& pose_;
  fba::Output& out_;
  const std::string mesh_name_;
  fba::TriangleMesh mesh_;
  fba::CameraModel camera_;
  std::vector<Eigen::Isometry3d> views_;
  std::size_t next_ = 0;
  fba::geometry::RenderOptions look_;
};

}  // namespace

FBA_COMPONENT(SimCamera);
