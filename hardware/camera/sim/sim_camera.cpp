// sim.camera: the simulated twin of a camera. Renders an object mesh (OBJ, PLY, STL...) from
// the pose it receives, or from a ring or an even spread of viewpoints over the upper
// hemisphere, with the given intrinsics: a shaded object on a background, optional noise.
#include <algorithm>
#include <filesystem>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <fba/component.hpp>
#include <fba/message_text.hpp>
#include <fba/types/frame.hpp>
#include <fba/types/pose.hpp>

#include "fba/geometry/mesh_io.hpp"
#include "fba/geometry/renderer.hpp"
#include "fba/geometry/viewpoints.hpp"
#include "object_placement_params.hpp"

namespace {

constexpr double kDegree = M_PI / 180.0;

class SimCamera final : public fba::Component {
 public:
  static constexpr fba::OptionalIn<fba::Pose> kPose{"pose", "render from this camera pose (world_from_camera), one frame per pose"};
  static constexpr fba::Out<fba::Frame> kFrame{"frame", "the rendered image with its intrinsics and pose"};
  // The object and its placement, the same parameters as sim.hand's (object_placement_params.hpp).
  static constexpr auto kMesh = fba::sim_hand::kObjectMesh;
  static constexpr auto kObjectX = fba::sim_hand::kObjectX;
  static constexpr auto kObjectY = fba::sim_hand::kObjectY;
  static constexpr auto kObjectYaw = fba::sim_hand::kObjectYaw;
  static constexpr auto kObjectRest = fba::sim_hand::kObjectRest;
  static constexpr auto kWorld =
      fba::Param<std::string>("world", "mesh",
                              "the world the object is rendered in: 'mesh', the mesh file's own coordinates (turned and moved by "
                              "object_rest, object_yaw, object_x, object_y, not raised), or 'table', where it rests on z = 0 (as sim.hand)")
          .choices({"mesh", "table"});
  static inline const auto kWorkspace =
      fba::Param<std::vector<double>>(
          "workspace", {},
          "[xmin, ymin, zmin, xmax, ymax, zmax]: where the task looks for the object (the carver's bounds), metres in the world "
          "the object is rendered in; an object larger than it or whose centre lies outside it is refused. Empty: not checked")
          .size({0, 6});
  static constexpr auto kWidth = fba::Param<int>("width", 640, "image width, pixels").range(16, 8192);
  static constexpr auto kHeight = fba::Param<int>("height", 480, "image height, pixels").range(16, 8192);
  static constexpr auto kFx = fba::Param<double>("fx", 600.0, "focal length, pixels").at_least(1);
  static constexpr auto kFy = fba::Param<double>("fy", 0.0, "vertical focal length, pixels; 0: same as fx").at_least(0);
  static constexpr auto kViewpoints =
      fba::Param<std::string>("viewpoints", "hemisphere", "without a pose input: where the views are").choices({"hemisphere", "ring"});
  static constexpr auto kViews = fba::Param<int>("views", 8, "number of viewpoints").range(1, 10000);
  static constexpr auto kMinElevation = fba::Param<double>("min_elevation", 0.0, "degrees above the horizon (hemisphere)").range(-90, 90);
  static constexpr auto kMaxElevation =
      fba::Param<double>("max_elevation", 90.0, "degrees above the horizon (hemisphere); the ring's elevation").range(-90, 90);
  static constexpr auto kDistance =
      fba::Param<double>("distance", 0.0, "metres from the object's centre; 0: far enough to frame it").at_least(0);
  static constexpr auto kObjectGrey = fba::Param<int>("object_grey", 210, "object brightness before shading").range(0, 255);
  static constexpr auto kBackgroundGrey = fba::Param<int>("background_grey", 25, "background brightness").range(0, 255);
  static constexpr auto kNoise = fba::Param<double>("noise", 0.0, "sensor noise, standard deviation in grey levels").range(0, 100);
  static constexpr fba::Param<std::int64_t> kSeed{"seed", 1, "noise seed"};
  // As vision.camera's, so that the twins offer one interface (a task may wire it either way).
  static constexpr fba::EventOut kLost{
      "lost", "the source stopped delivering frames (the last viewpoint, without a pose input); payload: the source"};

  static fba::Spec spec() {
    return fba::Spec::sensor("sim.camera", "Renders an object mesh as a calibrated camera would see it (the twin of vision.camera).")
        .add(kPose, kFrame, kMesh, kObjectX, kObjectY, kObjectYaw, kObjectRest, kWorld, kWorkspace, kWidth, kHeight, kFx, kFy, kViewpoints,
             kViews, kMinElevation, kMaxElevation, kDistance,
             kObjectGrey, kBackgroundGrey, kNoise, kSeed, kLost)
        .add(kMinElevation <= kMaxElevation)
        .check(kWorkspace, [](const fba::ParamValues& p) {
          const auto b = p(kWorkspace);
          if (!b.empty() && !(b[0] < b[3] && b[1] < b[4] && b[2] < b[5]))
            return std::string("workspace must be [xmin, ymin, zmin, xmax, ymax, zmax] with each min < its max");
          return std::string();
        });
  }

  explicit SimCamera(fba::Context& ctx) : ctx_(ctx), mesh_name_(mesh_name(ctx(kMesh))) {
    auto loaded = fba::geometry::load_mesh_with_warnings(ctx(kMesh));
    for (const auto& w : loaded.warnings) ctx.log().info("{}", w);
    const fba::sim_hand::ObjectPlacement placement = fba::sim_hand::object_placement(ctx);
    double raise = 0;
    mesh_ = fba::sim_hand::place_in_mesh_frame(loaded.mesh, placement, raise);
    if (ctx(kWorld) == "table")
      for (auto& v : mesh_.vertices) v.z() += static_cast<float>(raise);
    if (const auto b = ctx(kWorkspace); !b.empty())
      check_workspace(ctx, Eigen::AlignedBox3d(Eigen::Vector3d(b[0], b[1], b[2]), Eigen::Vector3d(b[3], b[4], b[5])));
    const int w = ctx(kWidth), h = ctx(kHeight);
    const double fx = ctx(kFx), fy = ctx(kFy) > 0 ? ctx(kFy) : fx;
    camera_ = fba::geometry::make_camera(w, h, fx, fy, (w - 1) / 2.0, (h - 1) / 2.0);
    const auto bounds = fba::geometry::mesh_bounds(mesh_);
    const Eigen::Vector3d centre = bounds.center();
    double distance = ctx(kDistance);
    if (distance == 0) distance = fba::geometry::framing_distance(bounds, w, h, std::min(fx, fy));
    const int n = ctx(kViews);
    const double lo = ctx(kMinElevation) * kDegree, hi = ctx(kMaxElevation) * kDegree;
    views_ = ctx(kViewpoints) == "ring" ? fba::geometry::ring_views(n, hi, distance, centre)
                                        : fba::geometry::hemisphere_views(n, lo, hi, distance, centre);
    look_.object_colour = cv::Vec3b::all(static_cast<unsigned char>(ctx(kObjectGrey)));
    look_.background_top = look_.background_bottom = cv::Vec3b::all(static_cast<unsigned char>(ctx(kBackgroundGrey)));
    look_.ambient = 0.35;
    look_.diffuse = 0.65;
    look_.noise_sigma = ctx(kNoise);
    look_.seed = static_cast<std::uint64_t>(ctx(kSeed));
    if (ctx(kPose).connected()) ctx.set_trigger({fba::TriggerPolicy::Any, 0});
    ctx.log().info("{}: {} triangles, {} viewpoints at {:.3f} m", mesh_name_, mesh_.triangles.size(), views_.size(), distance);
  }

  void process() override {
    fba::CameraModel camera = camera_;
    if (const auto pose = ctx_(kPose); pose.connected()) {
      camera.camera_from_world = pose.get().world_from_frame.inverse();
    } else {
      camera.camera_from_world = views_[next_++];
    }
    look_.seed += 1;  // each frame its own noise, the same sequence on every run
    auto frame = std::make_shared<fba::Frame>();
    frame->image = fba::geometry::render(mesh_, camera, look_).colour;
    frame->camera = camera;
    frame->has_pose = true;
    frame->stamp = static_cast<double>(ctx_.now_ns()) * 1e-9;
    frame->source = "sim_" + mesh_name_;
    auto out = ctx_(kFrame);
    frame->index = static_cast<int>(out.count());
    out.emit(std::shared_ptr<const fba::Frame>(std::move(frame)));
    if (!ctx_(kPose).connected() && next_ == views_.size()) {  // as a video file's end: lost, then done
      ctx_.emit(kLost, "sim_" + mesh_name_);
      ctx_.finish();
    }
  }

 private:
  // The frames' source names the object: a scanned object's mesh is model.obj (or textured.obj) in
  // a folder named for it, so that folder's name says which object it is.
  static std::string mesh_name(const std::filesystem::path& mesh) {
    const std::string stem = mesh.stem().string();
    const std::string folder = mesh.parent_path().filename().string();
    return (stem == "model" || stem == "textured") && !folder.empty() ? folder : stem;
  }

  // The object must stand where the task looks for it: elsewhere the views miss it or the carver
  // cuts it off, and the run would end on a symptom (no contour in an image, a model not joined to
  // the table) instead of the cause. Partly outside, it is carved cut off there: a warning.
  void check_workspace(fba::Context& ctx, const Eigen::AlignedBox3d& workspace) const {
    const Eigen::AlignedBox3d object = fba::geometry::mesh_bounds(mesh_);
    const Eigen::Vector3d size = object.sizes(), room = workspace.sizes();
    const bool too_large = (size.array() > room.array()).any();
    if (too_large || !workspace.contains(object.center())) {
      std::string why = too_large ? "it is larger than the workspace" : "its centre lies outside the workspace";
      // A mesh in millimetres is a thousand times too large, and then fits once divided.
      if (too_large && (size.array() / 1000 <= room.array()).all())
        why += "; divided by 1000 it would be " + sides(size / 1000) + ": the mesh may be in millimetres while metres are expected";
      throw std::runtime_error("the object '" + mesh_name_ + "' is outside the workspace: expected it within " + corners(workspace) +
                               " (" + sides(room) + ", in the '" + ctx(kWorld) + "' world), found it " + sides(size) + " centred at " +
                               point(object.center()) + " (object_x " + fba::number_text(ctx(kObjectX)) + ", object_y " +
                               fba::number_text(ctx(kObjectY)) + "): " + why);
    }
    const double beyond = std::max((object.max() - workspace.max()).maxCoeff(), (workspace.min() - object.min()).maxCoeff());
    if (beyond > 0)
      ctx.log().warn("the object '{}' ({} centred at {}) reaches {:.3f} m beyond the workspace {}: the model is carved cut off there",
                     mesh_name_, sides(size), point(object.center()), beyond, corners(workspace));
  }

  static std::string sides(const Eigen::Vector3d& s) { return fmt::format("{:.3f} x {:.3f} x {:.3f} m", s.x(), s.y(), s.z()); }
  static std::string point(const Eigen::Vector3d& p) { return fmt::format("({:.3f}, {:.3f}, {:.3f})", p.x(), p.y(), p.z()); }
  static std::string corners(const Eigen::AlignedBox3d& b) {
    return fmt::format("[{:.3f}, {:.3f}, {:.3f}, {:.3f}, {:.3f}, {:.3f}]", b.min().x(), b.min().y(), b.min().z(), b.max().x(), b.max().y(),
                       b.max().z());
  }

  fba::Context& ctx_;
  const std::string mesh_name_;
  fba::TriangleMesh mesh_;
  fba::CameraModel camera_;
  std::vector<Eigen::Isometry3d> views_;
  std::size_t next_ = 0;
  fba::geometry::RenderOptions look_;
};

}  // namespace

FBA_COMPONENT(SimCamera);
