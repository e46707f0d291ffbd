// vision.octree_carver: the paper's Algorithms 1 and 2. Each silhouette refines one octree
// model; regions of interest from grasp synthesis ask for detail where fingers may go. Every
// update is published as an immutable snapshot.
#include <cmath>
#include <limits>

#include <opencv2/imgcodecs.hpp>

#include <fba/component.hpp>
#include <fba/types/octree.hpp>
#include <fba/types/regions_of_interest.hpp>
#include <fba/types/silhouette.hpp>

#include "fba/geometry/renderer.hpp"
#include "fba/geometry/viewpoints.hpp"
#include "fba/vision/octree_carver.hpp"

namespace {

class OctreeCarverFilter final : public fba::Component {
 public:
  static fba::Spec spec() {
    return fba::Spec::filter("vision.octree_carver",
                             "Carves an octree model from silhouettes; refines where the occupancy or the grasp regions ask for it.")
        .input<fba::Silhouette>("silhouette", "a silhouette with its calibrated frame")
        .optional_input<fba::RegionsOfInterest>("regions", "where grasping needs detail (the grasp-specific criterion)")
        .output<fba::Octree>("octree", "the model after each update (immutable)")
        .param("max_depth", 6, "deepest level of the octree (the root is level 0)").range(1, 12)
        .param("min_node_size", 0.0, "metres: nodes this small or smaller are not split").range(0, std::nullopt)
        .param("occupancy_threshold", 0.0, "generic criterion: split a node whose silhouette occupancy is above this (and below 1)").range(0, 1)
        .param("bounds", std::vector<double>{}, "root box [xmin, ymin, zmin, xmax, ymax, zmax] in metres; empty: estimated from the first silhouettes")
        .param("bounds_views", 3, "silhouettes used to estimate the root box when bounds is empty").range(2, 100)
        .param("bounds_margin", 0.05, "estimated box grown by this share of its size on every side").range(0, 1)
        .param("threads", 0, "carving threads; 0 for one per core").range(0, 256)
        .event("bounds_estimated", "the root box was estimated from the first silhouettes; payload: the box")
        .event("updated", "a view was integrated; payload: views, nodes visited and refined so far");
  }

  explicit OctreeCarverFilter(fba::Context& ctx)
      : ctx_(ctx), silhouette_(ctx.input("silhouette")), regions_(ctx.input("regions")), out_(ctx.output("octree")),
        carver_(params(ctx)), bounds_views_(static_cast<std::size_t>(ctx.param<int>("bounds_views"))),
        margin_(ctx.param<double>("bounds_margin")) {
    const auto b = ctx.param<std::vector<double>>("bounds");
    if (!b.empty()) {
      if (b.size() != 6 || !(b[0] < b[3] && b[1] < b[4] && b[2] < b[5]))
        throw std::invalid_argument("bounds must be [xmin, ymin, zmin, xmax, ymax, zmax] with min < max");
      carver_.set_bounds(Eigen::AlignedBox3d(Eigen::Vector3d(b[0], b[1], b[2]), Eigen::Vector3d(b[3], b[4], b[5])));
      has_bounds_ = true;
    }
  }

  void process() override {
    if (regions_.has()) carver_.set_regions_of_interest(regions_.get<fba::RegionsOfInterest>());
    if (silhouette_.has()) {
      const auto& s = silhouette_.get<fba::Silhouette>();
      if (!first_camera_) first_camera_ = s.frame->camera;
      if (!has_bounds_) {
        pending_.push_back(s);  // the root box comes from the first few views together
        if (pending_.size() < bounds_views_) return;
        const auto box = fba::vision::OctreeCarver::estimate_bounds(pending_, margin_);
        carver_.set_bounds(box);
        has_bounds_ = true;
        ctx_.emit_event("bounds_estimated", fmt(box));
        carver_.add_views(pending_);
        pending_.clear();
      } else {
        carver_.add_view(s);
      }
    } else if (!has_bounds_ || !regions_.has()) {
      return;
    }
    publish();
  }

  void end_of_stream() override {
    if (!has_bounds_ && !pending_.empty())
      throw std::runtime_error("only " + std::to_string(pending_.size()) + " silhouettes arrived; " +
                               std::to_string(bounds_views_) + " are needed to estimate the root box (or set bounds)");
    if (ctx_.output_dir().empty() || !has_bounds_) return;
    const auto model = carver_.snapshot();
    const auto ply = ctx_.output_dir() / "model.ply";
    fba::vision::write_ply(*model, ply.string());
    ctx_.log().info("wrote {}", ply.string());
    if (first_camera_) {
      const auto png = ctx_.output_dir() / "model.png";
      if (!cv::imwrite(png.string(), picture(*model, *first_camera_))) ctx_.log().error("could not write {}", png.string());
    }
  }

 private:
  // The model seen from beside the first camera: turned 35 degrees around the model, raised 25
  // and framed whole, lit from the upper left, so that its sides and voxel steps show.
  static cv::Mat picture(const fba::Octree& model, const fba::CameraModel& first) {
    const Eigen::Vector3d centre = model.bounds.center();
    const Eigen::Matrix3d world_from_camera = first.camera_from_world.linear().transpose();
    const Eigen::Vector3d up = -(world_from_camera * Eigen::Vector3d::UnitY());
    Eigen::Vector3d eye = first.centre_in_world() - centre;
    eye = Eigen::AngleAxisd(35 * M_PI / 180, up) * eye;
    eye = Eigen::AngleAxisd(25 * M_PI / 180, up.cross(eye).normalized()) * eye;
    // Far enough that the whole root box is in the picture, whatever the lens.
    eye = eye.normalized() * fba::geometry::framing_distance(model.bounds, first.width, first.height,
                                                             std::min(first.K(0, 0), first.K(1, 1)));
    fba::CameraModel camera = first;
    camera.camera_from_world = fba::geometry::look_at(centre + eye, centre, up);
    fba::geometry::RenderOptions look;
    look.object_colour = {200, 200, 200};
    look.background_top = look.background_bottom = {255, 255, 255};
    look.light_towards_world = (camera.camera_from_world.linear().transpose() * Eigen::Vector3d(-0.5, -0.8, -1.0)).normalized();
    look.ambient = 0.3;
    look.diffuse = 0.7;
    return fba::geometry::render(fba::vision::occupied_surface_mesh(model), camera, look).colour;
  }

  static fba::vision::CarverParams params(fba::Context& ctx) {
    fba::vision::CarverParams p;
    p.max_depth = ctx.param<int>("max_depth");
    p.min_node_size = ctx.param<double>("min_node_size");
    p.occupancy_threshold = ctx.param<double>("occupancy_threshold");
    p.threads = ctx.param<int>("threads");
    return p;
  }

  static std::string fmt(const Eigen::AlignedBox3d& b) {
    char s[160];
    std::snprintf(s, sizeof s, "[%.4f, %.4f, %.4f, %.4f, %.4f, %.4f]", b.min().x(), b.min().y(), b.min().z(), b.max().x(),
                  b.max().y(), b.max().z());
    return s;
  }

  void publish() {
    const auto model = carver_.snapshot();
    const auto st = carver_.stats();
    const std::string progress = "views " + std::to_string(st.views) + ", nodes visited " + std::to_string(st.nodes_visited) +
                                 ", refined " + std::to_string(st.nodes_refined);
    ctx_.log().info("{} ({:.0f} ms carving so far)", progress, st.seconds * 1e3);
    ctx_.emit_event("updated", progress);
    out_.emit(model);
  }

  fba::Context& ctx_;
  fba::Input& silhouette_;
  fba::Input& regions_;
  fba::Output& out_;
  fba::vision::OctreeCarver carver_;
  const std::size_t bounds_views_;
  const double margin_;
  bool has_bounds_ = false;
  std::vector<fba::Silhouette> pending_;
  std::optional<fba::CameraModel> first_camera_;
};

}  // namespace

FBA_COMPONENT(OctreeCarverFilter);
