// vision.octree_carver: the paper's Algorithms 1 and 2. Each silhouette refines one octree
// model; regions of interest from grasp synthesis ask for detail where fingers may go. Every
// update is published as an immutable snapshot.
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>

#include <opencv2/imgcodecs.hpp>

#include <fba/component.hpp>
#include <fba/thread_pool.hpp>
#include <fba/types/octree.hpp>
#include <fba/types/regions_of_interest.hpp>
#include <fba/types/silhouette.hpp>

#include "fba/geometry/renderer.hpp"
#include "fba/geometry/viewpoints.hpp"
#include "fba/vision/octree_carver.hpp"

namespace {

class OctreeCarverFilter final : public fba::Component {
 public:
  static constexpr fba::In<fba::Silhouette> kSilhouette{"silhouette", "a silhouette with its calibrated frame"};
  static constexpr fba::OptionalIn<fba::RegionsOfInterest> kRegions{
      "regions", "where grasping needs detail (the grasp-specific criterion)"};
  static constexpr fba::Out<fba::Octree> kOctree{"octree", "the model after each update (immutable)"};
  static constexpr auto kMaxDepth = fba::Param<int>("max_depth", 6, "deepest level of the octree (the root is level 0)").range(1, 12);
  static constexpr auto kMinNodeSize = fba::Param<double>("min_node_size", 0.0, "metres: nodes this small or smaller are not split").at_least(0);
  static constexpr auto kOccupancyThreshold = fba::Param<double>(
      "occupancy_threshold", 0.0, "generic criterion: split a node whose silhouette occupancy is above this (and below 1)").range(0, 1);
  static inline const auto kBounds =
      fba::Param<std::vector<double>>("bounds", {}, "root box [xmin, ymin, zmin, xmax, ymax, zmax] in metres; empty: estimated from the first silhouettes")
          .size({0, 6});
  static constexpr auto kBoundsViews =
      fba::Param<int>("bounds_views", 3, "silhouettes used to estimate the root box when bounds is empty").range(2, 100);
  static constexpr auto kBoundsMargin =
      fba::Param<double>("bounds_margin", 0.05, "estimated box grown by this share of its size on every side").range(0, 1);
  static constexpr auto kDetailAfterViews = fba::Param<int>(
      "detail_after_views", 8,
      "nodes at depth >= detail_depth are split only once this many views are in (0: at once); lower it for tasks with fewer views")
                                                .range(0, 1000);
  static constexpr auto kDetailDepth =
      fba::Param<int>("detail_depth", 4, "the depth the model stops at until detail_after_views views are in").range(0, 19);
  static constexpr auto kMemoryBudgetMiB = fba::Param<double>(
      "memory_budget_mib", 4096, "MiB the model may use: a max_depth whose worst case exceeds it is refused, with the figure")
                                               .range(1, 1 << 20);
  static constexpr fba::EventOut kBoundsEstimated{"bounds_estimated", "the root box was estimated from the first silhouettes; payload: the box"};
  static constexpr fba::EventOut kUpdated{
      "updated",
      "a view was integrated; payload (JSON): views, carve_s, snapshot_s (of the previous update's snapshot), nodes_visited, "
      "nodes_refined, model_nodes, model_bytes, storage_bytes"};

  static fba::Spec spec() {
    return fba::Spec::filter("vision.octree_carver",
                             "Carves an octree model from silhouettes; refines where the occupancy or the grasp regions ask for it.")
        .add(kSilhouette, kRegions, kOctree, kMaxDepth, kMinNodeSize, kOccupancyThreshold, kBounds, kBoundsViews, kBoundsMargin,
             kDetailAfterViews, kDetailDepth, kMemoryBudgetMiB, kBoundsEstimated, kUpdated)
        .check(kBounds, [](const fba::ParamValues& p) {
          const auto b = p(kBounds);
          if (!b.empty() && !(b[0] < b[3] && b[1] < b[4] && b[2] < b[5]))
            return std::string("bounds must be [xmin, ymin, zmin, xmax, ymax, zmax] with each min < its max");
          return std::string();
        });
  }

  // The parameters were checked by the loader (the spec's checks): nothing left to refuse here.
  explicit OctreeCarverFilter(fba::Context& ctx)
      : ctx_(ctx), carver_(params(ctx)), bounds_views_(static_cast<std::size_t>(ctx(kBoundsViews))), margin_(ctx(kBoundsMargin)) {
    if (const auto b = ctx(kBounds); !b.empty()) {
      carver_.set_bounds(Eigen::AlignedBox3d(Eigen::Vector3d(b[0], b[1], b[2]), Eigen::Vector3d(b[3], b[4], b[5])));
      has_bounds_ = true;
    }
  }

  void process() override {
    const auto regions = ctx_(kRegions);
    const auto silhouette = ctx_(kSilhouette);
    if (regions.has()) carver_.set_regions_of_interest(regions.get());
    if (silhouette.has()) {
      const auto& s = silhouette.get();
      if (!first_camera_) first_camera_ = s.frame->camera;
      if (!has_bounds_) {
        pending_.push_back(s);  // the root box comes from the first few views together
        if (pending_.size() < bounds_views_) return;
        const auto box = fba::vision::OctreeCarver::estimate_bounds(pending_, margin_);
        carver_.set_bounds(box);
        has_bounds_ = true;
        ctx_.emit(kBoundsEstimated, fmt(box));
        carver_.add_views(pending_);
        pending_.clear();
      } else {
        carver_.add_view(s);
      }
    } else if (!has_bounds_ || !regions.has()) {
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
    p.max_depth = ctx(kMaxDepth);
    p.min_node_size = ctx(kMinNodeSize);
    p.occupancy_threshold = ctx(kOccupancyThreshold);
    p.detail_after_views = ctx(kDetailAfterViews);
    p.detail_depth = ctx(kDetailDepth);
    p.memory_budget = static_cast<std::size_t>(ctx(kMemoryBudgetMiB) * 1024 * 1024);
    // Carving borrows the task's threads instead of starting its own: the runtime, rendering
    // and carving share the cores.
    fba::ThreadPool& pool = ctx.thread_pool();
    p.parallel_for = [&pool](std::size_t n, const std::function<void(std::size_t)>& f) { pool.parallel_for(n, f); };
    return p;
  }

  static std::string fmt(const Eigen::AlignedBox3d& b) {
    char s[160];
    std::snprintf(s, sizeof s, "[%.4f, %.4f, %.4f, %.4f, %.4f, %.4f]", b.min().x(), b.min().y(), b.min().z(), b.max().x(),
                  b.max().y(), b.max().z());
    return s;
  }

  // The progress line and the `updated` event (kept in summary.json) give the update's figures.
  // The snapshot is timed by the carver when taken, so its time shows in the next line.
  void publish() {
    const auto model = carver_.snapshot();
    const auto st = carver_.stats();
    if (!st.updates.empty()) {
      const auto& u = st.updates.back();
      ctx_.log().info("views {}: carved in {:.1f} ms, {} nodes visited, {} refined; model {} nodes, {:.1f} MB ({:.1f} MB stored)",
                      u.views, u.carve_seconds * 1e3, u.nodes_visited, u.nodes_refined, u.model_nodes, u.model_bytes / 1e6,
                      u.storage_bytes / 1e6);
      const double snapshot_s = st.updates.size() > 1 ? st.updates[st.updates.size() - 2].snapshot_seconds : 0.0;
      char payload[320];
      std::snprintf(payload, sizeof payload,
                    "{\"views\": %zu, \"carve_s\": %.6f, \"snapshot_s\": %.6f, \"nodes_visited\": %zu, \"nodes_refined\": %zu, "
                    "\"model_nodes\": %zu, \"model_bytes\": %zu, \"storage_bytes\": %zu}",
                    u.views, u.carve_seconds, snapshot_s, u.nodes_visited, u.nodes_refined, u.model_nodes, u.model_bytes,
                    u.storage_bytes);
      ctx_.emit(kUpdated, payload);
    }
    ctx_(kOctree).emit(model);
  }

  fba::Context& ctx_;
  fba::vision::OctreeCarver carver_;
  const std::size_t bounds_views_;
  const double margin_;
  bool has_bounds_ = false;
  std::vector<fba::Silhouette> pending_;
  std::optional<fba::CameraModel> first_camera_;
};

}  // namespace

FBA_COMPONENT(OctreeCarverFilter);
