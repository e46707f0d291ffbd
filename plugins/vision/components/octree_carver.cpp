// vision.octree_carver: the paper's Algorithms 1 and 2. Each silhouette refines one octree
// model; regions of interest from grasp synthesis ask for detail where fingers may go. Every
// update is published as an immutable snapshot.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <optional>

#include <opencv2/imgcodecs.hpp>

#include <fba/component.hpp>
#include <fba/message_text.hpp>
#include <fba/thread_pool.hpp>
#include <fba/types/octree.hpp>
#include <fba/types/regions_of_interest.hpp>
#include <fba/types/silhouette.hpp>

#include "fba/geometry/mesh_io.hpp"
#include "fba/vision/model_picture.hpp"
#include "fba/vision/octree_carver.hpp"
#include "fba/vision/ply_leaves_parameter.hpp"

namespace {

class OctreeCarverFilter final : public fba::Component {
 public:
  static constexpr fba::In<fba::Silhouette> kSilhouette{"silhouette", "a silhouette with its calibrated frame"};
  static constexpr fba::OptionalIn<fba::RegionsOfInterest> kRegions{
      "regions", "where grasping needs detail (the grasp-specific criterion)"};
  static constexpr fba::Out<fba::Octree> kOctree{"octree", "the model after each update (immutable)"};
  // 9 at most: depth 10's worst case is more than the octree can address (OctreeNode::kMaxBlocks),
  // whatever memory_budget_mib says, so it could only be refused, or fail mid-run.
  static constexpr auto kMaxDepth = fba::Param<int>("max_depth", 6, "deepest level of the octree (the root is level 0)").range(1, 9);
  static constexpr auto kMinNodeSize = fba::Param<double>("min_node_size", 0.0, "metres: nodes this small or smaller are not split").at_least(0);
  static constexpr auto kOccupancyThreshold = fba::Param<double>(
      "occupancy_threshold", 0.5,
      "generic criterion: split a node whose share of its projection inside the silhouette is above this in a view where "
      "it lies on the outline; 0: split every node on the outline (uniform detail), 1: never (only the grasp criteria split)")
                                                  .range(0, 1);
  static constexpr auto kGenericDepth = fba::Param<int>(
      "generic_depth", 19,
      "the generic criterion splits only nodes shallower than this; deeper ones only where a grasp criterion asks (the "
      "paper's scheme: generic for the initial analysis, grasp-specific for the detail); 19: at every depth")
                                            .range(0, 19);
  static constexpr fba::Param<bool> kGraspContour{
      "grasp_contour", false,
      "grasp criterion without regions of interest: split a node whose projection holds a point of the outer or a hole's "
      "contour flatter than curvature_threshold (flat or concave: where fingers may go; a round hole's rim is concave)"};
  static constexpr auto kCurvatureThreshold = fba::Param<double>(
      "curvature_threshold", 0.01, "1/pixel: with grasp_contour, contour points of lower signed curvature (convex > 0) are graspable")
                                                  .range(-1, 1);
  static constexpr auto kSilhouetteTolerance = fba::Param<double>(
      "silhouette_tolerance", 0.7071067811865476,
      "pixels: how far from a projection a silhouette pixel still counts; sqrt(2)/2 is safe for exact masks, more allows for "
      "calibration or segmentation error")
                                                   .range(0, 64);
  static constexpr fba::Param<bool> kCarveOutsideView{
      "carve_outside_view", true,
      "a view whose silhouette lies wholly inside its image saw the whole object: it carves what projects outside the image "
      "(else space no view covers is never carved, and stays an obstacle to the arm); off: outside every image is unknown"};
  static constexpr fba::Param<bool> kCompareUniform{
      "compare_uniform", false,
      "also carve the same views one by one with uniform detail to the same depth (occupancy_threshold 0, no grasp "
      "criteria) and report both node counts in the `detail` event, after every update and at the end"};
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
  static constexpr auto kPlyLeaves = fba::vision::PlyLeavesParameter::kPlyLeaves;  // shared with grasp.synthesis
  static constexpr fba::EventOut kBoundsEstimated{"bounds_estimated", "the root box was estimated from the first silhouettes; payload: the box"};
  static constexpr fba::EventOut kSuspectModel{
      "suspect_model",
      "the model cannot be the object (no silhouettes, one view, empty, the whole root box, or a root box that the viewing "
      "cones contradict); payload: the reason. The run then fails with the same reason"};
  static constexpr fba::EventOut kModelWarning{
      "model_warning", "the model may not be the object (it is pressed against the root box's faces); payload: why"};
  static constexpr fba::EventOut kDetail{
      "detail",
      "where detail went, at the end and, with compare_uniform, after every update too (a run stopped by an event rule "
      "never reaches the end); payload (JSON): model_nodes, nodes_visited, and with compare_uniform the uniform carve's "
      "uniform_nodes, uniform_nodes_visited and saved_share (1 - model_nodes / uniform_nodes)"};
  static constexpr fba::EventOut kUpdated{
      "updated",
      "a view was integrated; payload (JSON): views, carve_s, snapshot_s (of the previous update's snapshot), nodes_visited, "
      "nodes_refined, model_nodes, model_bytes, storage_bytes"};

  static fba::Spec spec() {
    return fba::Spec::filter("vision.octree_carver",
                             "Carves an octree model from silhouettes; refines where the occupancy or the grasp regions ask for it.")
        .add(kSilhouette, kRegions, kOctree, kMaxDepth, kMinNodeSize, kOccupancyThreshold, kGenericDepth, kGraspContour, kCurvatureThreshold,
             kSilhouetteTolerance, kCarveOutsideView, kCompareUniform, kBounds, kBoundsViews, kBoundsMargin, kDetailAfterViews, kDetailDepth,
             kMemoryBudgetMiB, kPlyLeaves, kBoundsEstimated, kSuspectModel, kModelWarning, kDetail, kUpdated)
        .check(kBounds, [](const fba::ParamValues& p) {
          const auto b = p(kBounds);
          if (!b.empty() && !(b[0] < b[3] && b[1] < b[4] && b[2] < b[5]))
            return std::string("bounds must be [xmin, ymin, zmin, xmax, ymax, zmax] with each min < its max");
          return std::string();
        })
        .check(kMaxDepth, [](const fba::ParamValues& p) {
          // Refused at --check, with the figure, rather than when the carver is built.
          const std::size_t need = fba::vision::worst_case_bytes(p(kMaxDepth)) >> 20;
          if (double(need) <= p(kMemoryBudgetMiB)) return std::string();
          return "max_depth " + std::to_string(p(kMaxDepth)) + " may need up to " + std::to_string(need) +
                 " MiB, more than memory_budget_mib (" + fba::number_text(p(kMemoryBudgetMiB)) + "); raise it or lower max_depth";
        });
  }

  // The parameters were checked by the loader (the spec's checks): nothing left to refuse here.
  explicit OctreeCarverFilter(fba::Context& ctx)
      : ctx_(ctx),
        carver_(std::in_place, params(ctx)),
        bounds_views_(static_cast<std::size_t>(ctx(kBoundsViews))),
        margin_(ctx(kBoundsMargin)),
        compare_uniform_(ctx(kCompareUniform)),
        ply_leaves_(fba::vision::PlyLeavesParameter::read(ctx)) {
    if (compare_uniform_) {
      // Uniform detail to the same depth: every node on the outline split, no grasp criteria.
      fba::vision::CarverParams p = carver_->params();
      p.occupancy_threshold = 0;
      p.generic_depth = fba::vision::CarverParams{}.generic_depth;
      p.curvature_threshold = -std::numeric_limits<double>::infinity();
      uniform_.emplace(p);
    }
    if (const auto b = ctx(kBounds); !b.empty()) {
      const Eigen::AlignedBox3d box(Eigen::Vector3d(b[0], b[1], b[2]), Eigen::Vector3d(b[3], b[4], b[5]));
      carver_->set_bounds(box);
      if (uniform_) uniform_->set_bounds(box);
      has_bounds_ = true;
    }
  }

  void process() override {
    const auto regions = ctx_(kRegions);
    const auto silhouette = ctx_(kSilhouette);
    // The same regions again (synthesis asks after every model) change nothing: publishing the
    // same model would only bring the same request back, around the feedback loop for ever.
    bool new_regions = false;
    if (regions.has()) {
      const auto& boxes = regions.get().boxes;
      new_regions = !same_boxes(boxes, last_regions_);
      if (new_regions) {
        last_regions_ = boxes;
        carver_->set_regions_of_interest(regions.get());
      }
    }
    if (silhouette.has()) {
      const auto& s = silhouette.get();
      // A frame without a pose projects through an identity camera: the cones would not meet,
      // and the carve would be of nothing.
      if (!s.frame || !s.frame->has_pose)
        throw std::runtime_error("frame " + (s.frame ? std::to_string(s.frame->index) : std::string("?")) + " from '" +
                                 (s.frame ? s.frame->source : std::string()) +
                                 "' has no camera pose; the carver needs calibrated frames");
      cameras_.push_back(s.frame->camera);
      if (object_.empty()) object_ = fba::vision::object_name(s.frame->source);
      views_.push_back(geometry_of(s));
      if (!has_bounds_) {
        pending_.push_back(s);  // the root box comes from the first few views together
        if (pending_.size() < bounds_views_) return;
        const auto box = fba::vision::OctreeCarver::estimate_bounds(pending_, margin_);
        carver_->set_bounds(box);
        has_bounds_ = true;
        ctx_.emit(kBoundsEstimated, fmt(box));
        carver_->add_views(pending_);
        if (uniform_) {
          uniform_->set_bounds(box);
          for (const auto& v : views_) uniform_->add_view(v);
        }
        pending_.clear();
      } else {
        carver_->add_view(s);
        if (uniform_) uniform_->add_view(views_.back());
      }
    } else if (!has_bounds_ || !new_regions) {
      return;
    }
    publish();
  }

  void end_of_stream() override {
    if (!has_bounds_ && !pending_.empty())
      throw std::runtime_error("only " + std::to_string(pending_.size()) + " silhouettes arrived; " +
                               std::to_string(bounds_views_) + " are needed to estimate the root box (or set bounds)");
    if (views_.empty()) suspect("no silhouette arrived: no image had a target (check the images and the contour extraction's threshold)");
    auto model = carver_->snapshot();
    check_model(*model);
    report_detail(*model);
    if (ctx_.output_dir().empty()) return;
    write_outputs(*model);
  }

 private:
  static bool same_boxes(const std::vector<Eigen::AlignedBox3d>& a, const std::vector<Eigen::AlignedBox3d>& b) {
    return std::ranges::equal(a, b, [](const auto& x, const auto& y) { return x.min() == y.min() && x.max() == y.max(); });
  }

  // model.ply and the pictures (model.png, views.png). The carver and the checks' masks go first:
  // building the surfaces and rendering them set the run's peak memory.
  void write_outputs(const fba::Octree& model) {
    carver_.reset();
    uniform_.reset();
    views_ = {};
    const auto ply = ctx_.output_dir() / "model.ply";
    fba::geometry::write_ply(fba::vision::ply_mesh(model, ply_leaves_, cameras_), ply);
    ctx_.log().info("wrote {}", ply.string());
    fba::vision::ModelPictureOptions o;
    o.object = object_;
    o.views = cameras_;
    o.regions = last_regions_;
    for (const auto& [name, picture] : {std::pair{"model.png", &fba::vision::model_picture}, std::pair{"views.png", &fba::vision::views_picture}}) {
      const auto png = ctx_.output_dir() / name;
      if (!cv::imwrite(png.string(), picture(model, o))) ctx_.log().error("could not write {}", png.string());
    }
  }

  static fba::vision::CarverParams params(fba::Context& ctx) {
    fba::vision::CarverParams p;
    p.max_depth = ctx(kMaxDepth);
    p.min_node_size = ctx(kMinNodeSize);
    p.occupancy_threshold = ctx(kOccupancyThreshold);
    p.generic_depth = ctx(kGenericDepth);
    if (ctx(kGraspContour)) p.curvature_threshold = ctx(kCurvatureThreshold);
    p.silhouette_tolerance = ctx(kSilhouetteTolerance);
    p.carve_outside_view = ctx(kCarveOutsideView);
    p.detail_after_views = ctx(kDetailAfterViews);
    p.detail_depth = ctx(kDetailDepth);
    p.memory_budget = static_cast<std::size_t>(ctx(kMemoryBudgetMiB) * 1024 * 1024);
    // Carving borrows the task's threads instead of starting its own: the runtime, rendering
    // and carving share the cores.
    p.parallel_for = ctx.thread_pool().as_parallel_for();
    return p;
  }

  static std::string fmt(const Eigen::AlignedBox3d& b) {
    char s[160];
    std::snprintf(s, sizeof s, "[%.4f, %.4f, %.4f, %.4f, %.4f, %.4f]", b.min().x(), b.min().y(), b.min().z(), b.max().x(),
                  b.max().y(), b.max().z());
    return s;
  }

  // What the checks at the end need of a view: its mask (shared with the carver's copy) and its
  // camera, not the frame's image.
  static fba::Silhouette geometry_of(const fba::Silhouette& s) {
    auto frame = std::make_shared<fba::Frame>();
    frame->camera = s.frame->camera;
    frame->has_pose = true;
    frame->index = s.frame->index;
    fba::Silhouette kept;
    kept.mask = s.mask;
    kept.frame = std::move(frame);
    return kept;
  }

  // Fails the run with the reason, after the event that records it in summary.json.
  [[noreturn]] void suspect(const std::string& reason) {
    ctx_.emit(kSuspectModel, reason);
    throw std::runtime_error(reason);
  }

  // A model that cannot be the object is an error, not a result: the classic silent failures
  // (black, white or mis-thresholded images, one view, bounds in the wrong unit) all end in one.
  void check_model(const fba::Octree& model) {
    const std::size_t n = views_.size();
    if (n == 1) suspect("only 1 view was carved: a model from one view is its viewing cone, not the object (add views)");
    const Eigen::AlignedBox3d& root = model.bounds;
    // The viewing cones bound the object on their own; a root box orders of magnitude off
    // (millimetres for metres) leaves the object inside one voxel or outside the box.
    Eigen::AlignedBox3d cones;
    try {
      cones = fba::vision::OctreeCarver::estimate_bounds(views_, 0.0);
    } catch (const std::exception&) {
      cones.setEmpty();  // the cones do not bound a region (views from one side): nothing to compare
    }
    const double given = root.sizes().maxCoeff(), seen = cones.sizes().maxCoeff();
    if (!cones.isEmpty() && (!cones.intersects(root) || given > 100 * seen || given * 100 < seen)) {
      char ratio[64];
      std::snprintf(ratio, sizeof ratio, "%.3g", given / seen);
      suspect("the root box " + fmt(root) + " and the viewing cones' box " + fmt(cones) + " disagree (edge ratio " + ratio +
              (cones.intersects(root) ? "" : ", no overlap") + "): are the bounds in metres?");
    }
    double occupied = 0, on_faces = 0;  // volume, and area of the root's faces that occupied leaves cover
    model.for_each_occupied_leaf([&](const fba::OctreeCell& c) {
      const Eigen::AlignedBox3d b = c.box();
      occupied += b.volume();
      const Eigen::Vector3d e = b.sizes();
      for (int a = 0; a < 3; ++a) {
        const double face = e[(a + 1) % 3] * e[(a + 2) % 3];
        const double eps = 1e-9 * root.sizes()[a];
        if (std::abs(b.min()[a] - root.min()[a]) <= eps) on_faces += face;
        if (std::abs(b.max()[a] - root.max()[a]) <= eps) on_faces += face;
      }
    });
    const double face_share = on_faces / (6 * std::pow(root.sizes().x(), 2));
    ctx_.log().info("model: {:.1f}% of the root box's volume, {:.1f}% of its faces", 100 * occupied / root.volume(), 100 * face_share);
    if (occupied <= 0)
      suspect("the model is empty: the " + std::to_string(n) + " silhouettes have no common region inside the root box " +
              fmt(root) + " (check the calibration, the bounds and the silhouettes)");
    if (occupied >= 0.99 * root.volume())
      suspect("the model is the whole root box " + fmt(root) + ": the " + std::to_string(n) +
              " silhouettes carved nothing away (is the target the whole image, or the box far too small? With "
              "occupancy_threshold " + fmt::format("{}", carver_->params().occupancy_threshold) +
              " and no grasp criterion, a root whose share of every silhouette it meets is at most that is not split: lower it, 0 "
              "for uniform detail)");
    // An object inside its box touches the faces at a few places (the dino in its providers'
    // tight box: 3.8% of their area); a model pressed flat against them was cut by the box, or
    // its silhouettes hold background (the dino with contours.threshold 0: 22%). A box-shaped
    // object in a tight box does too, hence a warning, not a failure.
    if (face_share > 0.15) {
      char w[256];
      std::snprintf(w, sizeof w,
                    "the model covers %.0f%% of the root box's faces: the box cuts the object, or the silhouettes hold "
                    "background (check the bounds and the contours)",
                    100 * face_share);
      ctx_.log().warn("{}", w);
      ctx_.emit(kModelWarning, w);
    }
  }

  // Where detail went, against uniform refinement of the same views to the same depth.
  void report_detail(const fba::Octree& model) {
    const std::string payload = detail_json(model);
    if (uniform_) {
      const std::size_t u = uniform_->snapshot()->node_count;
      ctx_.log().info("detail: {} nodes against {} for uniform detail to depth {} ({:.1f}% fewer)", model.node_count, u,
                      uniform_->params().max_depth, 100.0 * (1.0 - double(model.node_count) / double(u)));
    }
    ctx_.emit(kDetail, payload);
  }

  // The `detail` figures as JSON: the model's nodes and the nodes visited, and with compare_uniform
  // the uniform carve's (carved view by view alongside, as this carver had the views, so that the
  // nodes visited compare too, and so that the figures are there after every update: a run stopped
  // by an event rule never reaches end_of_stream).
  std::string detail_json(const fba::Octree& model) {
    const auto st = carver_->stats();
    char payload[320];
    if (!uniform_) {
      std::snprintf(payload, sizeof payload, "\"model_nodes\": %zu, \"nodes_visited\": %zu", model.node_count, st.nodes_visited);
      return std::string("{") + payload + "}";
    }
    const std::size_t u = uniform_->snapshot()->node_count;
    std::snprintf(payload, sizeof payload,
                  "\"model_nodes\": %zu, \"nodes_visited\": %zu, \"uniform_nodes\": %zu, \"uniform_nodes_visited\": %zu, "
                  "\"saved_share\": %.4f",
                  model.node_count, st.nodes_visited, u, uniform_->stats().nodes_visited, 1.0 - double(model.node_count) / double(u));
    return std::string("{") + payload + "}";
  }

  // The progress line and the `updated` event (kept in summary.json) give the update's figures.
  // The snapshot is timed by the carver when taken, so its time shows in the next line.
  void publish() {
    const auto model = carver_->snapshot();
    const auto st = carver_->stats();
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
      // The run's totals: what the paper's refinement saves is counted in nodes visited.
      std::size_t visited = 0;
      double carve_s = 0;
      for (const auto& x : st.updates) {
        visited += x.nodes_visited;
        carve_s += x.carve_seconds;
      }
      std::snprintf(payload, sizeof payload,
                    "{\"views\": %zu, \"updates\": %zu, \"nodes_visited\": %zu, \"carve_s\": %.6f, \"model_nodes\": %zu, "
                    "\"model_bytes\": %zu}",
                    u.views, st.updates.size(), visited, carve_s, u.model_nodes, u.model_bytes);
      ctx_.report("carving", payload);
    }
    if (uniform_) ctx_.emit(kDetail, detail_json(*model));
    ctx_(kOctree).emit(model);
  }

  fba::Context& ctx_;
  std::optional<fba::vision::OctreeCarver> carver_;  // released before the outputs are written
  std::optional<fba::vision::OctreeCarver> uniform_;  // with compare_uniform: the same views, uniform detail
  const std::size_t bounds_views_;
  const double margin_;
  const bool compare_uniform_;
  const fba::vision::PlyLeaves ply_leaves_;
  bool has_bounds_ = false;
  std::vector<Eigen::AlignedBox3d> last_regions_;  // the regions of interest in force
  std::vector<fba::Silhouette> views_;  // every view so far (geometry_of): the checks at the end
  std::vector<fba::Silhouette> pending_;
  std::vector<fba::CameraModel> cameras_;  // the views' cameras, in arrival order: the PLY's and the pictures'
  std::string object_;                     // the object's name, from the first frame's source
};

}  // namespace

FBA_COMPONENT(OctreeCarverFilter);
